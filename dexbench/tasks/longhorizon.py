"""Long-horizon procedures: ordered stage graphs with progress in the state group."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import torch

from dexbench.assets import articulated, procedural
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.predicates import tilt_deg, xy_dist
from dexbench.tasks.templates import Placement, StageTask


class MakeCoffee(StageTask):
    name = "MakeCoffee"
    instruction = ("Pour the milk into the mug, put the mug under the coffee machine and "
                   "turn the lever.")
    description = ("Pour milk into a mug, place the mug under the coffee machine, and "
                   "activate the machine switch.")
    success_text = ("In order: pour the milk into the mug by tilting the bottle at least 70° "
                    "and bringing its spout close to the mug (within 0.06 m horizontally, "
                    "above the rim), place the mug under the coffee machine within about "
                    "0.09 m horizontally and 0.07 m vertically of its target spot, then "
                    "rotate the switch lever at least 35° from rest.")
    episode_seconds = 45.0
    stages = ("pour_milk", "place_mug", "turn_lever")
    placements: ClassVar = {
        "machine": Placement((0.25, 0.35), (-0.10, 0.10), (math.pi - 0.2, math.pi + 0.2)),
        "mug": Placement((-0.15, 0.05), (-0.30, -0.10)),
        "milk": Placement((-0.15, 0.05), (0.10, 0.30)),
    }
    pour_tilt, spout_radius = 70.0, 0.06
    spot_xy, spot_z = 0.09, 0.07
    lever_turn = math.radians(35.0)
    lever = "machine/lever"

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        objects = {"machine": articulated.add_coffee_machine(spec, "machine"),
                   "mug": procedural.add_mug(spec, "mug"),
                   "milk": articulated.add_milk_carton(spec, "milk")}
        self.initial_joints = {self.lever: objects["machine"].joints[self.lever][0]}
        return objects

    def stage_conditions(self, view: SceneView) -> torch.Tensor:
        rim = view.point_pos(*self.objects["mug"].points["rim"])
        spout = view.point_pos(*self.objects["milk"].points["spout"])
        tilt = tilt_deg(view.axis(*self.objects["milk"].axes["up"]))
        poured = (tilt >= self.pour_tilt) & (xy_dist(spout, rim) <= self.spout_radius) & (
            spout[:, 2] >= rim[:, 2])
        spot = view.point_pos(*self.objects["machine"].points["cup_spot"])
        mug = view.body_pos("mug")
        placed = (xy_dist(mug, spot) <= self.spot_xy) & ((mug[:, 2] - spot[:, 2]).abs()
                                                         <= self.spot_z)
        turned = (view.joint_pos(self.lever) - self.initial_joints[self.lever]).abs() >= (
            self.lever_turn)
        return torch.stack([poured, placed, turned], dim=1)

    def focus(self, view: SceneView) -> torch.Tensor:
        stage = self.completed(view).clamp(max=2)
        targets = torch.stack([view.body_pos("milk"), view.body_pos("mug"),
                               view.point_pos(*self.objects["machine"].points["lever_tip"])], 1)
        return targets[torch.arange(len(stage), device=stage.device), stage]
