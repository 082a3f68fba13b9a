"""Bimanual lifts of containers: a Dutch oven by its loop handles and a basket by its
rim, both with `TwoHandPlan` like the tray and the carton (`bimanual.py`)."""

from __future__ import annotations

from typing import ClassVar

import mujoco

from dexbench.assets import carried
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import TwoHandPlan
from dexbench.tasks.templates import LiftTask, Placement


@register
class BimanualLiftDutchOven(LiftTask):
    name = "BimanualLiftDutchOven"
    category = "bimanual"
    instruction = "Lift the Dutch oven with both hands."
    description = "Use both hands to grasp a Dutch oven and lift the cookware from the table."
    success_text = "The Dutch oven is lifted at least 0.30 m above its spawn height."
    episode_seconds = 10.0
    bimanual = True
    default_embodiment = "bimanual_floating_shadow"
    # The paper gives no reset region: ours, between the hands, handles towards them.
    placements: ClassVar = {"oven": Placement((0.05, 0.15), (-0.10, 0.10), (-0.3, 0.3))}
    lifted, lift_threshold = "oven", 0.30
    # As the tray's rim: each hand comes down palm-down over one loop handle (its middle
    # 3 cm towards the palm from where a cube would sit), fingers towards the pot, curls
    # them over the rim and pulls outward: the fingertips press the wall's inside and
    # carry the pot's 2.4 kg; the palms rise 0.36 m, past the 0.30 m.
    expert = TwoHandPlan("oven", {"right": "grip_yneg", "left": "grip_ypos"},
                         shift=(-0.03, 0.013, -0.02), lift=0.36)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"oven": carried.add_dutch_oven(spec, "oven")}


@register
class BimanualLiftBasket(LiftTask):
    name = "BimanualLiftBasket"
    category = "bimanual"
    instruction = "Lift the basket with both hands and keep it level."
    description = ("Use both hands to grasp and lift a basket while maintaining a level "
                   "carrying pose.")
    success_text = ("The basket is lifted at least 0.20 m above reset height and kept within "
                    "10° of level.")
    episode_seconds = 10.0
    bimanual = True
    default_embodiment = "bimanual_floating_shadow"
    # The paper gives no reset region: ours, the tray's, long axis between the hands.
    placements: ClassVar = {"basket": Placement((0.02, 0.08), (-0.10, 0.10), (-0.2, 0.2))}
    lifted, lift_threshold, max_tilt = "basket", 0.20, 10.0
    # As the tray: each hand hooks one short end's rim, fingers curled over it and inside.
    expert = TwoHandPlan("basket", {"right": "grip_yneg", "left": "grip_ypos"},
                         shift=(0.0, 0.043, 0.0))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"basket": carried.add_basket(spec, "basket")}
