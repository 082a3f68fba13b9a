"""Screwed parts: unscrew a tube's cap by pushing its grip fins round, a stroke at a time
(`TurnPlan` with `period`)."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco

from dexbench.assets import screwed
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import TurnPlan
from dexbench.tasks.templates import ArticulatedTask, Placement


@register
class UnscrewCap(ArticulatedTask):
    name = "UnscrewCap"
    category = "articulation"
    instruction = "Unscrew the cap of the tube."
    description = "Hold the tube and rotate the cap until it reaches the unscrewed state."
    success_text = ("The cap is rotated at least 98% of the way through its reachable "
                    "unscrewing range from its screwed-in start.")
    # A "fixate" task (8 s): the tube stands in a fixed stand, within every arm's reach.
    episode_seconds = 8.0
    placements: ClassVar = {"tube": Placement((0.0, 0.2), (-0.15, 0.15))}
    # Screwed in at the lower stop; one turn (counter-clockwise from above) unscrews it.
    joint, reset_at, threshold = "tube/thread", "lower", 0.98
    deviations = ("Ours where the paper says 'hold the tube': the tube stands in a fixed "
                  "stand, so the hand need not hold it; the cap unscrews in one turn, "
                  "turning in place (the thread's rise left out).",)
    # The fingers lean in at the cap from outside, on the side nearest the hand's start
    # (leaning out over the small cap they would land on it), push a fin a quarter turn
    # round, lift and come down behind the next: four strokes and a part to the turn,
    # pushed at 0.3 m/s to fit the 8 s.
    expert = TurnPlan("tube", "fin", lean=-0.75, period=math.pi / 2, push_speed=0.3)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"tube": screwed.add_capped_tube(spec, "tube")}
