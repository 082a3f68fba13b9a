"""A shopping basket's folding handles: hold the basket and raise one handle."""

from __future__ import annotations

from typing import ClassVar

import mujoco

from dexbench.assets import carried
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import HoldActuatePlan
from dexbench.tasks.templates import HoldActuateTask, Placement


@register
class LiftBasketHandle(HoldActuateTask):
    name = "LiftBasketHandle"
    category = "articulation"
    instruction = "Hold the basket and raise one of its handles."
    description = "Hold a shopping basket body and raise one of its articulated handles."
    success_text = ("Either handle hinge swings at least 50% of the way from its folded "
                    "reset position.")
    # The paper gives no reset region: ours, long side (and handle 0) towards the robot,
    # the basket's near wall clear of the hands' start poses.
    placements: ClassVar = {"basket": Placement((0.10, 0.18), (-0.10, 0.10), (-0.2, 0.2))}
    held, threshold = "basket", 0.5
    joints = ("basket/handle0", "basket/handle1")
    focus_point = ("basket", "grip0")
    # As the bucket's bail: the right hand's fingers, pointing at the hinge and tilted
    # down, slide under the near handle's grip tube (the pads aimed 1.2 cm below its
    # underside: aimed at it they land on top) and lift it along its arc; the basket's
    # weight holds it down.
    expert = HoldActuatePlan("basket", "basket/handle0", ("grip0", (-0.012, 0.0, 0.0)),
                             yaw=0.0, pitch=0.4, approach=(-1.0, 0.0, 0.8), done=0.7)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"basket": carried.add_shopping_basket(spec, "basket")}
