"""Functional pouring from stemmed glassware: a wine glass lifted and tipped over."""

from __future__ import annotations

from typing import ClassVar

import mujoco
import torch

from dexbench.assets import glassware
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, PourPlan
from dexbench.tasks.templates import Placement, PourTask


@register
class PourWineGlass(PourTask):
    name = "PourWineGlass"
    category = "functional"
    instruction = "Pick up the wine glass without touching its opening and tip it over."
    description = "Lift the wine glass and tilt it into a pouring orientation."
    success_text = ("The glass is lifted at least 0.20 m above its spawn height and tilted "
                    "at least 100° from vertical, all while not touching the opening of "
                    "the glass.")
    goal_marker = None
    placements: ClassVar = {"glass": Placement((0.02, 0.2), (-0.15, 0.15))}
    vessel, outlet = "glass", "rim"
    # Held by the stem like a person holds one, 2 cm under the bowl, the palm 2 cm nearer
    # than round a 5 cm cube (the stem is 9 mm thick): the closed fingers lie between
    # bowl and foot, which keep the tipped glass from sliding out along the stem (held
    # round the bowl it slid out, and the thumb lay on the opening). The hand turns about
    # its palm normal towards 155 degrees: an arm's hand lags its command, and turned
    # towards 137 an xArm7 poured 6 of 20 (155: 16 of 20). The glass passes 100 degrees
    # on the way, and the episode ends there.
    expert = PourPlan(
        GraspPlan("glass", point=("stem", (0.0, 0.0, 0.02)), shift=(0.0, 0.0, -0.02),
                  yaw="none", side=True, hand_shift="vessel"),
        tilt=2.7, turn_rate=0.8, squeeze=2.0, grasp_turn=0.17)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"glass": glassware.add_wine_glass(spec, "glass")}

    def success(self, view: SceneView) -> torch.Tensor:
        """Lift, tilt and no touch: the paper pours nowhere in particular."""
        return ((self.lift(view, self.vessel) >= self.lift_threshold)
                & (self._tilt(view) >= self.min_tilt) & ~self.touched(view, self.vessel))

    def progress(self, view: SceneView) -> torch.Tensor:
        lifted = (self.lift(view, self.vessel) / self.lift_threshold).clamp(0.0, 1.0)
        tilted = (self._tilt(view) / self.min_tilt).clamp(0.0, 1.0)
        return (lifted + tilted) / 2.0
