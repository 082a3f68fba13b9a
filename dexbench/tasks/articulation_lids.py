"""Hinged lids: lift the lid of a storage box and of a cooking pot."""

from __future__ import annotations

from typing import ClassVar

import mujoco

from dexbench.assets import lidded
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import TurnPlan
from dexbench.tasks.templates import ArticulatedTask, Placement

# Tab towards the robot (yaw near 0, like the laptop), far enough forward that a 12-14 cm
# tall container clears the hand's start pose.
FRONT_REGION = ((-0.15, 0.0), (-0.15, 0.15), (-0.25, 0.25))
# The hand, palm down with its fingers pointing at the hinge and tilted down, comes down
# in front of the tab (from high enough that its fingers, still turning, clear the lid:
# from lower they knocked a box over), slides its finger pads under the tab and lifts it
# along its arc; the container's own weight holds it down.
FRONT_TAB = {"pitch": 0.6, "approach": (-1.0, 0.0, 0.8)}


@register
class LiftLid(ArticulatedTask):
    name = "LiftLid"
    category = "articulation"
    instruction = "Lift the lid of the box."
    description = "Interact with an articulated object and lift its lid to the open state."
    success_text = "The lid hinge reaches at least 80% of its full opening range."
    placements: ClassVar = {"box": Placement(*FRONT_REGION)}
    joint = "box/hinge"
    expert = TurnPlan("box", "tab", **FRONT_TAB)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"box": lidded.add_storage_box(spec, "box")}


@register
class GraspPot(ArticulatedTask):
    name = "GraspPot"
    category = "articulation"
    instruction = "Open the pot's lid."
    description = ("Manipulate the articulated pot lid until its lid joint reaches the "
                   "intended state.")
    success_text = "The lid hinge reaches at least 80% of its full opening range."
    placements: ClassVar = {"pot": Placement(*FRONT_REGION)}
    joint = "pot/hinge"
    expert = TurnPlan("pot", "tab", **FRONT_TAB)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"pot": lidded.add_lidded_pot(spec, "pot")}
