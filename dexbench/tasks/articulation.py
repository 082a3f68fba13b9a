"""Articulated objects: open, close and operate jointed mechanisms."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco

from dexbench.assets import articulated
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.primitive import _Articulated
from dexbench.tasks.templates import Placement


class OpenDrawer(_Articulated):
    name = "OpenDrawer"
    category = "articulation"
    instruction = "Open the drawer."
    description = "Grasp and pull an articulated drawer outward from the cabinet."
    success_text = "The drawer slides out at least 80% of its full travel."
    # The cabinet faces -x, towards the robot.
    placements: ClassVar = {"cabinet": Placement((0.15, 0.30), (-0.15, 0.15),
                                                 (math.pi - 0.2, math.pi + 0.2))}
    joint = "cabinet/drawer"
    threshold = 0.8

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        info = articulated.add_drawer_cabinet(spec, "cabinet")
        self.initial_joints = {self.joint: info.joints[self.joint][0]}
        return {"cabinet": info}

    def focus(self, view):
        return view.point_pos(*self.objects["cabinet"].points["handle"])


class OpenLaptop(_Articulated):
    name = "OpenLaptop"
    category = "articulation"
    instruction = "Hold the laptop base and open the lid."
    description = "Hold the laptop base and open the laptop lid around its hinge."
    success_text = ("The lid swings at least 70% of the way from its slightly-open reset "
                    "angle near -15° toward the fully open limit near -110°.")
    episode_seconds = 8.0
    bimanual = True
    default_embodiment = "bimanual_floating_shadow"
    placements: ClassVar = {"laptop": Placement((-0.30, 0.0), (-0.20, 0.20), (-0.2, 0.2))}
    joint = "laptop/hinge"
    threshold = 0.70
    reset_angle = math.radians(-15.0)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        info = articulated.add_laptop(spec, "laptop")
        self.initial_joints = {self.joint: self.reset_angle}
        return {"laptop": info}
