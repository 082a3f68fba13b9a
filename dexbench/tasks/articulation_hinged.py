"""Side-hinged doors: open a cupboard and a microwave by hooking the handle and pulling
it round along the door's arc (`SwingPlan`)."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco

from dexbench.assets import hinged
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, SwingPlan
from dexbench.tasks.templates import ArticulatedTask, Placement

# Cabinet and microwave face -x, towards the robot, like OpenDrawer's; their doors swing
# out towards it, hinged on the robot's left.
FACING_ROBOT = (math.pi - 0.2, math.pi + 0.2)


def hook_and_swing(obj: str, joint: str, shift: tuple[float, float, float] = (
        0.0, 0.0, -0.025)) -> SwingPlan:
    """The hand hangs in front of the handle bar, palm towards the door, curls its
    fingers behind the bar and pulls it round the hinge. `shift` brings the bar nearer
    the palm than a cube would be, so the fingers close behind it, not under it."""
    return SwingPlan(GraspPlan(obj, point="handle", yaw="body", pitch=math.pi / 2,
                               shift=shift, carry_high=False), joint)


@register
class OpenCabinet(ArticulatedTask):
    name = "OpenCabinet"
    category = "articulation"
    instruction = "Open the cabinet door."
    description = "Open the cabinet by actuating target joint joint_11 from its reset pose."
    success_text = ("The target cabinet joint moves at least 80% of the way toward its "
                    "limit from its reset pose.")
    placements: ClassVar = {"cabinet": Placement((0.15, 0.30), (-0.15, 0.15), FACING_ROBOT)}
    joint = "cabinet/joint_11"
    focus_point = ("cabinet", "handle")
    expert = hook_and_swing("cabinet", joint)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cabinet": hinged.add_door_cabinet(spec, "cabinet", joint="joint_11")}



@register
class OpenMicrowave(ArticulatedTask):
    name = "OpenMicrowave"
    category = "articulation"
    instruction = "Open the microwave door."
    description = "Grasp and pull an articulated microwave door until it reaches the open state."
    success_text = "The door hinge reaches at least 80% of its full opening range."
    # 5 cm further back than the cabinet: the wider, deeper microwave turned by its reset
    # yaw would otherwise reach the hand's fingers at their start.
    placements: ClassVar = {"microwave": Placement((0.20, 0.32), (-0.15, 0.15), FACING_ROBOT)}
    joint = "microwave/door"
    focus_point = ("microwave", "handle")
    expert = hook_and_swing("microwave", joint)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"microwave": hinged.add_microwave(spec, "microwave")}

