"""Functional manipulation: use an object for its purpose (pour, strike, ...)."""

from __future__ import annotations

from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import objects, procedural
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.predicates import dist, tilt_deg, zone_touched
from dexbench.tasks.templates import Placement, TabletopTask, uniform_points


class FunctionalPourMug(TabletopTask):
    name = "FunctionalPourMug"
    category = "functional"
    instruction = "Pick up the mug by its body or handle and pour it out at the target."
    description = "Grasp a mug, lift it from the table, and rotate it into a pouring posture."
    success_text = ("The mug is lifted at least 0.2 m, tilted at least 100°, and its rim "
                    "brought within 0.10 m of the goal, all while not touching the rim.")
    placements: ClassVar = {"mug": Placement((-0.10, 0.20), (-0.35, 0.35))}
    goal_marker = "goal"
    lift_threshold, min_tilt, rim_tolerance = 0.20, 100.0, 0.10

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"mug": procedural.add_mug(spec, "mug"),
                "goal": objects.add_goal_marker(spec, "goal", radius=0.02)}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (-0.05, 0.25), (-0.30, 0.30), (0.30, 0.30))

    def _rim(self, view: SceneView) -> torch.Tensor:
        return view.point_pos(*self.objects["mug"].points["rim"])

    def _tilt(self, view: SceneView) -> torch.Tensor:
        return tilt_deg(view.axis(*self.objects["mug"].axes["up"]))

    def _rim_touched(self, view: SceneView) -> torch.Tensor:
        touched = torch.zeros(view.body_pos("mug").shape[0], dtype=torch.bool,
                              device=view.body_pos("mug").device)
        for zone in self.objects["mug"].zones:
            touched |= zone_touched(view, zone)
        return touched

    def success(self, view: SceneView) -> torch.Tensor:
        return ((self.lift(view, "mug") >= self.lift_threshold)
                & (self._tilt(view) >= self.min_tilt)
                & (dist(self._rim(view), view.goal) <= self.rim_tolerance)
                & ~self._rim_touched(view))

    def progress(self, view: SceneView) -> torch.Tensor:
        lifted = (self.lift(view, "mug") / self.lift_threshold).clamp(0.0, 1.0)
        tilted = (self._tilt(view) / self.min_tilt).clamp(0.0, 1.0)
        near = (1.0 - dist(self._rim(view), view.goal) / 0.5).clamp(0.0, 1.0)
        return (lifted + tilted + near) / 3.0
