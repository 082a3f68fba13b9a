"""Functional manipulation: use an object for its purpose (pour, strike, ...)."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np

from dexbench.assets import procedural
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, PourPlan, handle_between, task_goal
from dexbench.tasks.templates import Placement, PourTask, uniform_points


@register
class FunctionalPourMug(PourTask):
    name = "FunctionalPourMug"
    category = "functional"
    instruction = "Pick up the mug by its body or handle and pour it out at the target."
    description = "Grasp a mug, lift it from the table, and rotate it into a pouring posture."
    success_text = ("The mug is lifted at least 0.2 m, tilted at least 100°, and its rim "
                    "brought within 0.10 m of the goal, all while not touching the rim.")
    placements: ClassVar = {"mug": Placement((-0.10, 0.20), (-0.35, 0.35))}
    vessel, outlet = "mug", "rim"
    # Held low, at 4.5 cm, the palm 1.5 cm nearer than for a cube, the fingers tipped 10
    # degrees down (the forearm would rest on the table), its handle anywhere but between
    # the palm and the mug. The fingers close twice as hard as the hook synergy (the
    # Shadow hand's are weak); the index finger stays open and the thumb swings aside:
    # both would otherwise lie at the rim once the mug is tipped and settled in the hand.
    expert = PourPlan(
        GraspPlan("mug", point=(0.0, 0.0, 0.045), shift=(-0.01, 0.0, -0.015), yaw="body",
                  yaw_offset=handle_between("mug", -0.3, 1.25 * math.pi), side=True,
                  synergy="hook", target=task_goal, goal_point="rim"),
        tilt=1.75, turn_rate=0.8, squeeze=2.0, grasp_turn=0.17,
        overrides=((r"FFJ", 0.0), (r"THJ5$", -1.05), (r"THJ4$", 1.22)))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"mug": procedural.add_mug(spec, "mug")}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (-0.05, 0.25), (-0.30, 0.30), (0.30, 0.30))
