"""Functional use of kitchen objects and tools: a pan onto its burner, a cup out of its
rack, a hammer onto a nail (paper appendix, "Functional")."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import kitchen, procedural, tools
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, StrikePlan, task_goal
from dexbench.tasks.predicates import dist, tilt_deg, zone_touched
from dexbench.tasks.templates import Placement, TabletopTask, uniform_points

RACK_CLEARANCE = 0.03  # m the cup's bottom rises above the rods' tops before moving across
NAIL_HOME = 0.065  # m: the expert stops pressing once the nail is in this far
LET_GO_ACROSS, LET_GO_ABOVE = 0.01, 0.04  # m: a pan's centre this close over the burner
RACK_RADIUS = 0.06  # m: a cup bottom this close to the rack's axis is still in the rack


def _stove_target(env: DexEnv) -> np.ndarray:
    return env.task.point(env.view, "stove", "target").cpu().numpy()


def _across_bar(env: DexEnv) -> np.ndarray:
    """Fingers square across the handle, turned by the hand's own `bar_yaw`."""
    return np.full(env.num_envs, math.pi / 2 + env.embodiment.hand.bar_yaw)


def _over_burner(env: DexEnv) -> np.ndarray:
    """Let go of a pan hanging tilted once it is centred just above the grate: its low
    rim rests there and stops it coming down further; let go, it falls flat."""
    off = env.task.point(env.view, "pan", "centre").cpu().numpy() - _stove_target(env)
    return (np.linalg.norm(off[:, :2], axis=1) < LET_GO_ACROSS) & (off[:, 2] < LET_GO_ABOVE)


@register
class GraspPan(TabletopTask):
    name = "GraspPan"
    category = "functional"
    instruction = "Pick up the pan by its handle and set it flat on the burner."
    description = ("Manipulate a frying pan into a controlled flat pose while avoiding contact "
                   "with the cooking surface.")
    success_text = ("The pan face is brought within 10° of flat and its center within 0.025 m "
                    "of the burner target, all while not touching the cooking surface.")
    # The handle points at the robot; the stove's range starts past the pan's rim.
    placements: ClassVar = {
        "pan": Placement((-0.15, -0.05), (-0.30, 0.30), (math.pi - 0.4, math.pi + 0.4)),
        "stove": Placement((0.20, 0.40), (-0.20, 0.20), (-0.3, 0.3), clearance=-0.3)}
    # The hand carries the pan from its place to the stove: midway between their centres.
    workspace = ((placements["pan"].centre[0] + placements["stove"].centre[0]) / 2,
                 (placements["pan"].centre[1] + placements["stove"].centre[1]) / 2, 0.0)
    max_tilt, tolerance = 10.0, 0.025
    # Across the handle near the rim (the shortest lever for the pan's weight), the palm
    # low so the fingers close under the handle. The pan tilts 10-30 deg in the Shadow
    # hand's grip, so its low rim meets the grate first: it is let go just above it. A
    # squeeze (as the hammer's) or turning the hand to level it loosens this grip. Each
    # hand holds the handle on its own diagonal across the palm (`HandSpec.bar_yaw`).
    expert = GraspPlan("pan", point=("handle", (-0.03, 0.0, -0.014)), shift=(0.03, 0.0, -0.03),
                       yaw="body", yaw_offset=_across_bar, target=_stove_target,
                       goal_point=("centre", (0.0, 0.0, -0.005)), release=True,
                       let_go=_over_burner)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"pan": kitchen.add_pan(spec, "pan"), "stove": kitchen.add_stove(spec, "stove")}

    def _miss(self, view: SceneView) -> torch.Tensor:
        return dist(self.point(view, "pan", "centre"), self.point(view, "stove", "target"))

    def _tilt(self, view: SceneView) -> torch.Tensor:
        return tilt_deg(view.axis(*self.objects["pan"].axes["up"]))

    def success(self, view: SceneView) -> torch.Tensor:
        return ((self._tilt(view) <= self.max_tilt) & (self._miss(view) <= self.tolerance)
                & ~self.touched(view, "pan"))

    def progress(self, view: SceneView) -> torch.Tensor:
        return 1.0 - self._miss(view) / 0.5


def _out_of_rack(env: DexEnv) -> np.ndarray:
    """Where the held cup's bottom goes: straight up out of the rack's rods first, then to
    the goal (moving across earlier drags it along the rods and tips it)."""
    task, view = env.task, env.view
    bottom = task.point(view, "cup", "bottom").cpu().numpy()
    top = task.point(view, "rack", "top").cpu().numpy()
    inside = ((bottom[:, 2] < top[:, 2] + RACK_CLEARANCE / 2)
              & (np.linalg.norm((bottom - top)[:, :2], axis=1) < RACK_RADIUS))
    above = np.column_stack([bottom[:, :2], top[:, 2] + RACK_CLEARANCE])
    return np.where(inside[:, None], above, task_goal(env))


@register
class RetrieveCup(TabletopTask):
    name = "RetrieveCup"
    category = "functional"
    instruction = "Take the cup out of the rack and stand it upright on the target."
    description = "Remove a cup from a rack and place it upright at the commanded goal."
    success_text = ("The cup comes within 0.04 m of the goal on the table and stays within "
                    "15° of upright.")
    goal_marker = 0.02
    placements: ClassVar = {"rack": Placement((0.05, 0.15), (0.10, 0.35), (-0.3, 0.3))}
    attached: ClassVar = {"cup": ("rack", "slot")}
    max_tilt, tolerance = 15.0, 0.04
    expert = GraspPlan("cup", point=("rim", (0.0, 0.0, -0.025)), yaw="none", hand_shift="rim",
                       target=_out_of_rack, goal_point=("bottom", (0.0, 0.0, -0.003)),
                       release=True)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cup": procedural.add_cup(spec, "cup"), "rack": kitchen.add_cup_rack(spec, "rack")}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (0.0, 0.15), (-0.40, -0.25), (0.0, 0.0))

    def _miss(self, view: SceneView) -> torch.Tensor:
        return dist(self.point(view, "cup", "bottom"), view.goal[:, :3])

    def success(self, view: SceneView) -> torch.Tensor:
        upright = tilt_deg(view.axis(*self.objects["cup"].axes["up"])) <= self.max_tilt
        return upright & (self._miss(view) <= self.tolerance)

    def progress(self, view: SceneView) -> torch.Tensor:
        return 1.0 - self._miss(view) / 0.6


def _nail_home(env: DexEnv) -> np.ndarray:
    return (env.task.driven(env.view) >= NAIL_HOME).cpu().numpy()


@register
class FunctionalHammerStrike(TabletopTask):
    name = "FunctionalHammerStrike"
    category = "functional"
    instruction = "Pick up the hammer and drive the nail into the board with it."
    description = ("Use a hammer to strike or press a nail into a board while avoiding unsafe "
                   "fingertip contact.")
    success_text = ("The nail is pressed in at least 0.06 m, and the hand does not touch the "
                    "nail head directly.")
    deviations = ("Stricter than the paper: a hand touching the nail head at any time in the "
                  "episode fails it, so only the hammer can drive the nail.",)
    placements: ClassVar = {
        "stand": Placement((-0.10, 0.0), (-0.20, 0.0), (-0.3, 0.3)),
        "board": Placement((0.0, 0.15), (0.20, 0.30), (-0.3, 0.3))}
    attached: ClassVar = {"hammer": ("stand", "hammer")}
    contact_objects = ("hammer",)
    focus_point = ("hammer", "grip")
    memory_size = 1  # 1 once a hand has touched the nail head
    depth = 0.06
    # Across the handle, near the head (a short lever for the press), face over the head;
    # squeezed: at the synergy's own closure the heavy head swings the handle 50 deg
    # round in the fingers as soon as it is lifted. The mount's IK takes the hand's wrist
    # as commanded (`commanded_hand`): the lifted head swings the Shadow wrist, and an
    # arm chasing each swing flung the hammer out of the hand (fr3_shadow 0.2 -> 1.0).
    expert = StrikePlan(GraspPlan("hammer", point=("head", (-0.075, 0.0, 0.0)),
                                  shift=(0.03, 0.0, -0.045), yaw="body", yaw_offset=math.pi / 2,
                                  squeeze=2.0, commanded_hand=True, hand_shift="tool"),
                        face="face", on="board", at="nail_head", done=_nail_home,
                        hover=0.03, depth=0.02, press=1.0)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"hammer": tools.add_hammer(spec, "hammer"),
                "stand": tools.add_hammer_stand(spec, "stand"),
                "board": tools.add_nail_board(spec, "board")}

    def driven(self, view: SceneView) -> torch.Tensor:
        """(N,) how far (m) the nail has gone into the board."""
        return -view.joint_pos("board/nail")

    def update(self, view: SceneView) -> None:
        (head,) = self.objects["board"].zones
        touched = zone_touched(view, head).to(view.memory.dtype)
        view.memory[:, 0] = torch.maximum(view.memory[:, 0], touched)

    def success(self, view: SceneView) -> torch.Tensor:
        return (self.driven(view) >= self.depth) & (view.memory[:, 0] < 0.5)

    def progress(self, view: SceneView) -> torch.Tensor:
        return self.driven(view) / self.depth
