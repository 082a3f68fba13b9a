"""Articulated objects: open, close and operate jointed mechanisms."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np

from dexbench.assets import articulated
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.dex_env import DexEnv
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, TurnPlan
from dexbench.tasks.templates import ArticulatedTask, Placement

PULL_LEAD = 0.1  # m ahead of the drawer handle the hand keeps pulling towards


def drawer_pulled(env: DexEnv) -> np.ndarray:
    """A point ahead of the handle along the drawer's opening direction: keep pulling."""
    body, handle = env.task.objects["cabinet"].points["handle"]
    view = env.view
    ahead = view.point_pos(body, handle) + PULL_LEAD * view.axis(body, (1.0, 0.0, 0.0))
    return ahead.cpu().numpy()


@register
class OpenDrawer(ArticulatedTask):
    name = "OpenDrawer"
    category = "articulation"
    instruction = "Open the drawer."
    description = "Grasp and pull an articulated drawer outward from the cabinet."
    success_text = "The drawer slides out at least 80% of its full travel."
    # The cabinet faces -x, towards the robot.
    placements: ClassVar = {"cabinet": Placement((0.15, 0.30), (-0.15, 0.15),
                                                 (math.pi - 0.2, math.pi + 0.2))}
    joint = "cabinet/drawer"
    # Hand hanging in front of the handle, palm towards the cabinet: the fingers curl
    # behind the bar and the hand pulls along the drawer's axis.
    expert = GraspPlan("cabinet", point="handle", yaw="body", pitch=math.pi / 2,
                       target=drawer_pulled, goal_point="handle", carry_high=False)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cabinet": articulated.add_drawer_cabinet(spec, "cabinet")}

    def focus(self, view):
        return self.point(view, "cabinet", "handle")


@register
class OpenLaptop(ArticulatedTask):
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
    joint, threshold, reset_at = "laptop/hinge", 0.70, math.radians(-15.0)
    # Fingers tilted down slide under the raised front edge of the lid, from the front,
    # and lift it up and over; the base's own weight holds it down.
    expert = TurnPlan("laptop", "lid_edge", direction=-1.0, pitch=0.6,
                      approach=(-1.0, 0.0, 0.3))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"laptop": articulated.add_laptop(spec, "laptop")}
