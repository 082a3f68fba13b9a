"""Functional manipulation: use an object for its purpose (pour, strike, ...)."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import procedural, vessels
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, HandleBetween, PourPlan, object_point, task_goal
from dexbench.tasks.templates import Placement, PourTask, uniform_points

# Shadow hand, side grasp round a vessel: the index finger stays open and the thumb swings
# aside, both of which would otherwise lie at the rim once the vessel is tipped and
# settled in the hand (other hands have no actuators these match).
KEEP_OFF_RIM = ((r"FFJ", 0.0), (r"THJ5$", -1.05), (r"THJ4$", 1.22))
# Sharpa hand, open: the thumb drawn back, each joint at its range's end away from the
# palm (left open, it stands 3 cm off the palm, into a tall vessel's side or shoulder).
THUMB_BACK = ((r"_thumb_CMC_FE_ctrl$", -0.17), (r"_thumb_MCP_FE_ctrl$", -0.52),
              (r"_thumb_(CMC|MCP)_AA_ctrl$", -0.35))


def body_pour(vessel: str, outlet: str) -> PourPlan:
    """Pour a handle-less vessel 10 cm tall (cup, can) held round its body: as the mug, but
    held at 4 cm and 1 cm further out along the fingers (the thumb's base would reach the
    rim band), and turned 115 degrees, as the vessel lags the hand's turn by some 15.
    Round, it may be held from any side (an arm's reach: `PourPlan.round_body`)."""
    return PourPlan(
        GraspPlan(vessel, point=(0.0, 0.0, 0.04), shift=(0.0, 0.0, -0.015), yaw="none",
                  side=True, synergy="hook", target=task_goal, goal_point=outlet,
                  hand_shift="vessel"),
        tilt=2.0, turn_rate=0.8, squeeze=2.0, grasp_turn=0.17, overrides=KEEP_OFF_RIM,
        round_body=True)


@register
class FunctionalPourMug(PourTask):
    name = "FunctionalPourMug"
    category = "functional"
    instruction = "Pick up the mug by its body or handle and pour it out at the target."
    description = "Grasp a mug, lift it from the table, and rotate it into a pouring posture."
    success_text = ("The mug is lifted at least 0.2 m, tilted at least 100°, and its rim "
                    "brought within 0.10 m of the goal, all while not touching the rim.")
    placements: ClassVar = {"mug": Placement((-0.10, 0.20), (-0.35, 0.35))}
    vessel, outlet = "mug", "rim"
    # Held low, at 4.5 cm, the palm 1.5 cm nearer than for a cube, the fingers tipped 10
    # degrees down (the forearm would rest on the table), its handle anywhere but between
    # the palm and the mug. The fingers close twice as hard as the hook synergy (the
    # Shadow hand's are weak); the index finger stays open and the thumb swings aside:
    # both would otherwise lie at the rim once the mug is tipped and settled in the hand.
    # The hand turns 100 degrees, and on up to 120 until the mug is tipped 110: the
    # Shadow hand's weak grip lets the mug settle 10-25 degrees further over than its
    # turn, a firm grip (Sharpa's, Wuji's) holds it at the turn (100 left it at 90).
    expert = PourPlan(
        GraspPlan("mug", point=(0.0, 0.0, 0.045), shift=(-0.01, 0.0, -0.015), yaw="body",
                  yaw_offset=HandleBetween("mug", -0.3, 1.25 * math.pi), side=True,
                  synergy="hook", target=task_goal, goal_point="rim", hand_shift="vessel"),
        tilt=1.75, turn_rate=0.8, squeeze=2.0, grasp_turn=0.17,
        overrides=KEEP_OFF_RIM, tip=110.0, further=0.35, round_body=True)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"mug": procedural.add_mug(spec, "mug")}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (-0.05, 0.25), (-0.30, 0.30), (0.30, 0.30))


@register
class GraspCup(PourTask):
    name = "GraspCup"
    category = "functional"
    instruction = "Pick up the cup without touching its rim and pour it out at the target."
    description = ("Grasp a cup, lift it from the table, and rotate it into a pouring posture "
                   "while avoiding the rim.")
    success_text = ("The cup is lifted at least 0.3 m, tilted at least 100°, and its rim "
                    "brought within 0.10 m of the goal, all while not touching the rim band "
                    "(its top 1 cm).")
    placements: ClassVar = {"cup": Placement((-0.15, 0.15), (-0.15, 0.15))}
    vessel, outlet, lift_threshold = "cup", "rim", 0.30
    expert = body_pour("cup", "rim")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cup": procedural.add_cup(spec, "cup")}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (0.0, 0.35), (-0.25, 0.25), (0.30, 0.30))


@register
class FunctionalPourCan(PourTask):
    name = "FunctionalPourCan"
    category = "functional"
    instruction = "Pick up the opened can without touching its lip and pour it out at the target."
    description = "Grasp a soup can, lift it from the table, and rotate it into a pouring posture."
    success_text = ("The can is lifted at least 0.2 m, tilted at least 100°, and its lip "
                    "brought within 0.10 m of the goal, all while not touching the lip.")
    deviations = ("The authors pour over a bowl; here the goal is a marker 0.2 m above the "
                  "table with no container under it.",)
    placements: ClassVar = {"can": Placement((-0.15, 0.0), (-0.15, 0.15))}
    vessel, outlet = "can", "lip"
    expert = body_pour("can", "lip")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"can": vessels.add_can(spec, "can")}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (0.0, 0.15), (-0.15, 0.15), (0.20, 0.20))


@register
class GraspBleach(PourTask):
    name = "GraspBleach"
    category = "functional"
    instruction = "Pick up the bleach bottle, keep off its nozzle, and pour at the target."
    description = ("Grasp a bleach bottle, lift it, and rotate it into a pouring posture while "
                   "avoiding the nozzle.")
    success_text = ("The bottle is lifted at least 0.3 m, tilted at least 100° from vertical, "
                    "and its nozzle brought within 0.02 m (horizontally) of the goal, all "
                    "while not touching the nozzle.")
    deviations = ("As in the authors' code, the nozzle's distance to the goal is horizontal.",)
    placements: ClassVar = {"bleach": Placement((0.1, 0.3), (-0.4, 0.0), (-0.3, 0.3))}
    vessel, outlet, lift_threshold = "bleach", "nozzle", 0.30
    tolerance, horizontal = 0.02, True
    # Held round its middle from its side, the fingers round its front (nozzle) end: the
    # pour turn about the palm normal tips the nozzle forwards, over the fingertips. The
    # thumb closes too (`power`: the 0.4 kg jug slides out of a thumbless hook in the
    # Wuji and Sharpa hands), but the Shadow hand's, swung aside, stays open as in its
    # hook; the Sharpa hand's open thumb, which would tip the 26 cm jug over on the way
    # in, comes in drawn back. The jug's centre sits 5 mm short of the cube's place along
    # the fingers (by trial: 5 mm nearer the palm, the Sharpa hand loses it mid-pour).
    expert = PourPlan(
        GraspPlan("bleach", point="centre", shift=(-0.005, 0.0, -0.015), yaw="body",
                  side=True, synergy="power", target=task_goal, goal_point="nozzle",
                  hand_shift="vessel"),
        tilt=2.0, turn_rate=0.8, squeeze=2.0,
        overrides=(*KEEP_OFF_RIM, (r"THJ[123]$", 0.0)), open_overrides=THUMB_BACK)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"bleach": vessels.add_bleach_bottle(spec, "bleach")}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (0.0, 0.4), (0.0, 0.4), (0.30, 0.30))


@register
class GraspKettle(PourTask):
    name = "GraspKettle"
    category = "functional"
    instruction = "Pick up the kettle by its handle and pour from its spout into the mug."
    description = ("Grasp a kettle, lift it from the table, and rotate it into a pouring "
                   "posture while avoiding the spout.")
    success_text = ("The kettle is lifted at least 0.15 m, tilted at least 45°, and its spout "
                    "brought within 0.05 m (horizontally) of the mug, all while not touching "
                    "the spout.")
    deviations = ("The paper's goal is the mug on the table, as in the authors' code; like "
                  "theirs, the spout's distance to it is horizontal.",)
    goal_marker = None
    placements: ClassVar = {  # the spout faces the mug's side (+y), as in the authors' scene
        "kettle": Placement((-0.05, 0.15), (-0.3, -0.1), (math.pi / 2 - 0.3, math.pi / 2 + 0.3)),
        "mug": Placement((-0.15, 0.15), (0.05, 0.3))}
    vessel, outlet, lift_threshold, min_tilt = "kettle", "spout", 0.15, 45.0
    tolerance, horizontal = 0.05, True
    # Hooked round the top of its handle bar, palm outside, the fingers between bar and
    # body: the kettle swings forwards in the hand by itself (its centre is 10 cm ahead
    # of the bar) and settles some 55 degrees over, the spout down; the hand turns with it
    # only a little, and carries the spout 9 cm above the mug's rim. The open hand stands
    # 2 cm off the bar (the Shadow hand's 1.7, rounded up), whatever its palm's and
    # fingers' thickness: nearer, a thick hand pushes the kettle off; further, the bar
    # is not in the fingers' hook.
    expert = PourPlan(
        GraspPlan("kettle", point=("handle", (0.0, 0.0, 0.025)), shift=(-0.02, 0.0, -0.02),
                  yaw="body", yaw_offset=-math.pi / 2, side=True, synergy="hook",
                  target=object_point("mug", "rim", 0.09), goal_point="spout",
                  standoff=0.02, hand_shift="handle"),
        tilt=0.3, turn_rate=0.8, about=(-1.0, 0.0, 0.0), squeeze=2.0)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"kettle": vessels.add_kettle(spec, "kettle"),
                "mug": procedural.add_mug(spec, "mug")}

    def target(self, view: SceneView) -> torch.Tensor:
        return self.point(view, "mug", "rim")
