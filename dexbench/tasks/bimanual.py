"""Bimanual coordination: two hands stabilise, transfer or lift together."""

from __future__ import annotations

from typing import ClassVar

import mujoco
import torch

from dexbench.assets import objects
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.predicates import tilt_deg
from dexbench.tasks.templates import Placement, TabletopTask


class BimanualLiftTray(TabletopTask):
    name = "BimanualLiftTray"
    category = "bimanual"
    instruction = "Lift the tray with both hands and keep it level."
    description = "Use both hands to lift a tray while keeping the carried surface level."
    success_text = ("The tray is lifted at least 0.20 m above reset height and kept within "
                    "10° of level.")
    episode_seconds = 10.0
    bimanual = True
    default_embodiment = "bimanual_floating_shadow"
    placements: ClassVar = {"tray": Placement((0.02, 0.08), (-0.10, 0.10), (-0.2, 0.2))}
    lift_threshold, max_tilt = 0.20, 10.0

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"tray": objects.add_tray(spec, "tray")}

    def _tilt(self, view: SceneView) -> torch.Tensor:
        return tilt_deg(view.axis(*self.objects["tray"].axes["up"]))

    def success(self, view: SceneView) -> torch.Tensor:
        return (self.lift(view, "tray") >= self.lift_threshold) & (
            self._tilt(view) <= self.max_tilt)

    def progress(self, view: SceneView) -> torch.Tensor:
        level = (self._tilt(view) <= self.max_tilt).to(torch.float64)
        return level * self.lift(view, "tray") / self.lift_threshold
