"""Articulated objects: open, close and operate jointed mechanisms."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np

from dexbench.assets import articulated, cutters, office
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.dex_env import DexEnv
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import (
    EITHER,
    GraspPlan,
    HoldActuatePlan,
    PinchPlan,
    PressPlan,
    TurnPlan,
)
from dexbench.tasks.templates import SPEED_NOTE, ArticulatedTask, HoldActuateTask, Placement

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
    focus_point = ("cabinet", "handle")
    # Hand hanging in front of the handle, palm towards the cabinet: the fingers curl
    # behind the bar and the hand pulls along the drawer's axis.
    expert = GraspPlan("cabinet", point="handle", yaw="body", pitch=math.pi / 2,
                       target=drawer_pulled, goal_point="handle", carry_high=False)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cabinet": articulated.add_drawer_cabinet(spec, "cabinet")}


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
    # and lift it up and over; the base's own weight holds it down. The pads go 3 cm past
    # the edge: Wuji's soft fingers (~0.8 N at the tip) bend under the lid (~4 N at its
    # edge) resting nearer their tips, and stall it at ~25 degrees on every arm (0 of 8
    # at 12 mm, 5-6 of 8 at 3 cm; every other hand 5-6 of 8 at 3 cm too). (Deeper once
    # pressed the lid shut on the way in: the hand then came straight from its start,
    # across the lid, not over the top.)
    expert = TurnPlan("laptop", "lid_edge", direction=-1.0, pitch=0.6,
                      approach=(-1.0, 0.0, 0.3), under=0.03)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"laptop": articulated.add_laptop(spec, "laptop")}


# Folder and stapler lie with their free edge towards the robot (yaw pi): the pushing
# hand's fingers, pointing at the hinge and tilted down, slide under the raised edge
# and lift it along its arc.
FACING_ROBOT = (math.pi - 0.2, math.pi + 0.2)
UNDER_EDGE = {"yaw": math.pi, "pitch": 0.6, "approach": (1.0, 0.0, 0.3)}
BELOW = (0.0, 0.0, -0.018)  # the finger pads' centre, under the edge they lift


@register
class OpenFlatFolder(HoldActuateTask):
    name = "OpenFlatFolder"
    category = "articulation"
    instruction = "Hold the folder and open its flap."
    description = "Hold a flat folder and open its top flap around the hinge."
    success_text = ("The flap hinge opens at least 60% of the way from its near-closed "
                    "reset position.")
    placements: ClassVar = {"folder": Placement((0.0, 0.0), (-0.2, 0.2), FACING_ROBOT)}
    held, joints, threshold, reset_at = "folder", ("folder/flap",), 0.6, math.radians(10.0)
    # The base's weight holds it down: one hand lifts the flap up and over.
    expert = HoldActuatePlan("folder", "folder/flap", ("flap_edge", BELOW), done=0.75,
                             side=EITHER, **UNDER_EDGE)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"folder": office.add_flat_folder(spec, "folder")}


@register
class OpenStapler(HoldActuateTask):
    name = "OpenStapler"
    category = "articulation"
    instruction = "Hold the stapler and open its arm."
    description = "Hold a stapler body and open the upper arm around its hinge."
    success_text = "The shell hinge opens at least 20% of the way from its closed reset position."
    placements: ClassVar = {"stapler": Placement((0.0, 0.0), (-0.2, 0.2), FACING_ROBOT)}
    held, joints, threshold = "stapler", ("stapler/arm",), 0.2
    # The left hand's finger tips pin the base's back end (behind the hinge) to the table.
    # The pads go under the arm's very front, clear of the base's front face.
    expert = HoldActuatePlan("stapler", "stapler/arm", ("arm_lip", (0.005, 0.0, -0.008)),
                             done=0.35, **UNDER_EDGE,
                             hold=PressPlan("stapler", ("base", (-0.08, 0.0, 0.026)),
                                            yaw=math.pi / 2))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"stapler": office.add_stapler(spec, "stapler")}


@register
class SlideUtilityKnife(HoldActuateTask):
    name = "SlideUtilityKnife"
    category = "articulation"
    instruction = "Slide the utility knife's blade out and lift the knife."
    description = "Hold a utility knife body and slide its blade out from the handle."
    success_text = ("The blade slides out at least 40% of its travel from the retracted reset "
                    "pose, and the whole knife is lifted at least 0.2 m off its support.")
    placements: ClassVar = {"knife": Placement((-0.05, 0.05), (-0.15, 0.05), (0.0, 0.0))}
    held, joints, threshold, lift_threshold = "knife", ("knife/blade",), 0.4, 0.2
    deviations = (SPEED_NOTE,)
    # On the table the right hand's palm, fingers tilted down, pushes the thumb knob
    # forward (the knife's own friction holds it; aiming 12 mm off its centre line meets
    # it with a finger, not a gap between two) and backs off; the left hand, waiting
    # beside, then pinches the handle's rear half between thumb and index tips low on its
    # sides (clear of the knob; higher up they roll the 2 cm handle over) and lifts it;
    # the blade's friction keeps it out. Power grasps slip off the flat handle.
    expert = HoldActuatePlan("knife", "knife/blade", ("slider", (0.0, 0.012, 0.003)),
                             yaw=math.pi, pitch=1.3, approach=(-1.0, 0.0, 1.0), done=0.45,
                             release=True,
                             then=PinchPlan("knife", point=(-0.03, 0.0, 0.001), axis="blade",
                                            lift=0.25, width=0.026))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"knife": cutters.add_utility_knife(spec, "knife")}


@register
class SqueezeScissors(HoldActuateTask):
    name = "SqueezeScissors"
    category = "articulation"
    instruction = "Hold the scissors and squeeze them closed."
    description = ("Hold and squeeze a pair of scissors so the hinge moves toward the closed "
                   "state.")
    success_text = "Either blade hinge closes at least 50% of the way from its reset position."
    # Blades away from the robot, finger rings towards it.
    placements: ClassVar = {"scissors": Placement((0.05, 0.05), (0.0, 0.0), (-0.3, 0.3))}
    held, threshold, reset_at = "scissors", 0.5, "upper"
    joints = ("scissors/blade0", "scissors/blade1")
    # The left hand pins ring 1, no finger tip on ring 0's blade (Allegro's wide-spread
    # fingers put one there and held the scissors open); the right hand's hanging fingers
    # push ring 0 towards it.
    expert = HoldActuatePlan("scissors", "scissors/blade0", "ring0", direction=-1.0,
                             done=0.7, hold=PressPlan("scissors", "ring1", pitch=0.5,
                                                      keep_off="scissors/blade0"))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"scissors": cutters.add_scissors(spec, "scissors")}
