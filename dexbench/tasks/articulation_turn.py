"""Turned parts: rotate a dial knob to either end of its travel, and raise a bucket's bail
handle from where it lies; both push a part's tip round its hinge (`TurnPlan`)."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco

from dexbench.assets import turned
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import TurnPlan
from dexbench.tasks.templates import ArticulatedTask, Placement

# The bucket's bail lies towards the robot (yaw near 0, like the lidded box's tab), far
# enough forward that the 13 cm pail clears the hand's start pose.
BUCKET_REGION = ((-0.15, 0.0), (-0.15, 0.15), (-0.25, 0.25))
BAIL_REST = math.radians(85.0)


@register
class RotateKnob(ArticulatedTask):
    name = "RotateKnob"
    category = "articulation"
    instruction = "Turn the knob all the way."
    description = "Grasp or contact an articulated knob and rotate it to the target setting."
    success_text = "The knob is turned to either end of its 180° joint limits."
    # Like the faucet: the bar's tip points away from the robot, the hand pushes it round.
    placements: ClassVar = {"knob": Placement((0.3, 0.5), (-0.2, 0.2),
                                              (math.pi - 0.3, math.pi + 0.3))}
    # Reset in the middle; progress counts either way from there, so 95% of the 90 deg to
    # either stop (within 4.5 deg of it) is "at that end".
    joint, reset_at, threshold = "knob/dial", 0.0, 0.95
    deviations = ("Ours where the paper says 'to either end': within 4.5° of a stop (95% "
                  "of the 90° from the middle reset to it).",)
    # The fingers lean out along the bar (tips down on its end): an arm's hand reaches
    # the far-out knob only reaching forward, never hanging straight down; and it turns
    # the bar's tip towards the robot (either end counts), never out of reach.
    expert = TurnPlan("knob", "tip", direction=0.0, lean=1.2)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"knob": turned.add_knob(spec, "knob")}


@register
class GraspBucket(ArticulatedTask):
    name = "GraspBucket"
    category = "articulation"
    instruction = "Raise the bucket's handle."
    description = "Reach for an articulated bucket and raise its handle from the resting pose."
    success_text = ("The handle hinge rotates at least 40% of its reachable range from its "
                    "near-limit reset pose.")
    placements: ClassVar = {"bucket": Placement(*BUCKET_REGION)}
    # Reset 3 deg off the lower stop, the bail lying towards the robot.
    joint, reset_at, threshold = "bucket/handle", -BAIL_REST + 0.05, 0.4
    # As for the lids: palm down, fingers towards the hinge and tilted down, the pads slide
    # under the grip tube and lift it along its arc; the pail's weight holds it down.
    expert = TurnPlan("bucket", "grip", pitch=0.6, approach=(-1.0, 0.0, 0.8))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"bucket": turned.add_bucket(spec, "bucket", rest=BAIL_REST)}
