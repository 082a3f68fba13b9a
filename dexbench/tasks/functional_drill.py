"""Functional use of a power drill: its bit brought onto a marked point (paper appendix,
"Functional")."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import drills
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan
from dexbench.tasks.predicates import dist, tilt_deg
from dexbench.tasks.templates import Placement, TabletopTask

FORK_CLEARANCE = 0.03  # m the bit tip rises above the stand's fork before moving across
FORK_RADIUS = 0.05  # m: a tip this close to the fork's axis, below it, is still in the stand
NEAR = 0.06  # m: the bit tip this close over the mark leads the last of the way itself


def _drill_target(env: DexEnv) -> np.ndarray:
    """Where the held drill's bit tip goes: straight up out of the stand's fork first
    (moving across earlier drags the chuck and bit through the prongs), then over the
    mark, led by the drill's root (on the grip's line: the drill's swing in the fingers
    does not move it; led by the swinging tip, the hand chases the swing), and from
    `NEAR` onto the mark by the tip itself (the held drill leans 5-20 degrees, which puts
    the tip up to 6 cm off the root's plumb line)."""
    task, view = env.task, env.view
    tip = task.point(view, "drill", "tip").cpu().numpy()
    fork = task.point(view, "stand", "fork").cpu().numpy()
    inside = ((tip[:, 2] < fork[:, 2] + FORK_CLEARANCE / 2)
              & (np.linalg.norm((tip - fork)[:, :2], axis=1) < FORK_RADIUS))
    above = np.column_stack([tip[:, :2], fork[:, 2] + FORK_CLEARANCE])
    mark = task.point(view, "board", "mark").cpu().numpy()
    root = view.body_pos("drill").cpu().numpy()
    over = mark + np.array([0.0, 0.0, drills.TIP_DEPTH])
    far = np.linalg.norm((mark - tip)[:, :2], axis=1) > NEAR
    led = np.where(far[:, None], tip + over - root, mark)
    return np.where(inside[:, None], above, led)


@register
class FunctionalDrillApply(TabletopTask):
    name = "FunctionalDrillApply"
    category = "functional"
    instruction = "Pick up the drill by its grip and put the bit's tip on the red mark."
    description = ("Pick up a drill and bring its bit onto a marked target point on the work "
                   "surface.")
    success_text = ("The bit tip is brought within 0.025 m of the target while the drill is "
                    "held near-vertical, all while not touching the chuck or bit.")
    deviations = ("The paper gives no angle for near-vertical: here the bit points within "
                  "15° of straight down (the 15° of RetrieveCup's upright).",)
    # The stand is turned so the drill's grip points away from the board (-y), give or
    # take 0.3 rad: the drill is carried to the board along its grip (carried across it,
    # the drill rolls some 45 degrees over in the fingers and stays there); its housing
    # stays 9 cm or more to the right of the hand's home, clear of the open fingers.
    placements: ClassVar = {
        "stand": Placement((-0.10, 0.0), (-0.25, -0.15), (-math.pi / 2 - 0.3, -math.pi / 2 + 0.3)),
        "board": Placement((-0.05, 0.15), (0.10, 0.28), (-0.5, 0.5), clearance=0.0)}
    attached: ClassVar = {"drill": ("stand", "drill")}
    contact_objects = ("drill",)
    focus_point = ("drill", "grip")
    max_tilt, tolerance = 15.0, 0.025
    # Palm-down over the level grip, the fingers across it round the drill's centre of
    # mass, the index finger next to the housing, the grip 1 cm nearer the palm than the
    # hammer's handle (by trial: 1 cm either way, or the grasp 1.5 cm along the grip,
    # holds the drill less often); squeezed, as the hammer's grip: the 0.95 kg drill
    # hangs from the fingers. The IK takes the Shadow hand's weak wrist as commanded:
    # the carried drill swings it (some 0.5 rad either way), and a mount turned to take
    # out each swing drove it further until the drill rolled out of the fingers (over
    # half the episodes on the floating hand, a third on an arm).
    expert = GraspPlan("drill", point="grip", shift=(0.03, 0.0, -0.035), yaw="body",
                       yaw_offset=math.pi / 2, squeeze=2.0, target=_drill_target,
                       goal_point="tip", commanded_hand=True)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"drill": drills.add_drill(spec, "drill"),
                "stand": drills.add_drill_stand(spec, "stand"),
                "board": drills.add_workpiece(spec, "board")}

    def _miss(self, view: SceneView) -> torch.Tensor:
        return dist(self.point(view, "drill", "tip"), self.point(view, "board", "mark"))

    def _tilt(self, view: SceneView) -> torch.Tensor:
        """(N,) degrees between the drill's bit and straight down."""
        return tilt_deg(view.axis(*self.objects["drill"].axes["up"]))

    def success(self, view: SceneView) -> torch.Tensor:
        return ((self._miss(view) <= self.tolerance) & (self._tilt(view) <= self.max_tilt)
                & ~self.touched(view, "drill"))

    def progress(self, view: SceneView) -> torch.Tensor:
        return 1.0 - self._miss(view) / 0.5
