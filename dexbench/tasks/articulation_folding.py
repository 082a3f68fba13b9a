"""Folding hand-held things: unfold a pair of glasses' temples."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco

from dexbench.assets import foldables
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import HoldActuatePlan, SequencePlan, Step
from dexbench.tasks.templates import HoldActuateTask, Placement

UNDER = (0.0, 0.0, -0.016)  # the finger pads' centre, under the temple they lift
# Each temple from its own side of the front (temple a's +x, temple b's -x): fingers
# across the temple (along it, the thin temple slips into a gap between two fingers),
# tilted down, passing over nothing but the front's low rim (over the other temple, they
# press it flat; along the temple from its end, the second one is blocked by the first,
# then standing beside that end).
FROM_A = {"yaw": math.pi, "pitch": 0.3, "approach": (1.0, 0.0, 0.05)}
FROM_B = {"yaw": 0.0, "pitch": 0.3, "approach": (-1.0, 0.0, 0.05)}


@register
class OpenGlasses(HoldActuateTask):
    name = "OpenGlasses"
    category = "articulation"
    instruction = "Hold the glasses and unfold both temple arms."
    description = "Hold a pair of glasses and unfold both temple arms."
    success_text = ("Both temple hinges independently open at least 80% of the way from "
                    "their slightly-open reset position.")
    # The paper gives no reset region or angle: ours, the front pointing away from the
    # robot (temple a on the left, hinged at the near end), both temples 15 deg open.
    placements: ClassVar = {"glasses": Placement((-0.05, 0.05), (-0.10, 0.10),
                                                 (math.pi / 2 - 0.2, math.pi / 2 + 0.2))}
    held, threshold, require_all = "glasses", 0.8, True
    joints = ("glasses/temple_a", "glasses/temple_b")
    reset_at = math.radians(15.0)
    focus_point = ("glasses", "bridge")
    # The front's weight holds it down. The left hand's fingers slide under temple a's
    # raised end from the left and swing it up to standing (as a folder's flap); then,
    # while the left hand moves out of the way, the right hand's do the same to temple b
    # from the right.
    expert = SequencePlan((
        Step(HoldActuatePlan("glasses", "glasses/temple_a", ("tip_a", UNDER), done=0.9,
                             side="left", **FROM_A)),
        Step(HoldActuatePlan("glasses", "glasses/temple_b", ("tip_b", UNDER), done=0.9,
                             **FROM_B)),
    ))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"glasses": foldables.add_glasses(spec, "glasses")}
