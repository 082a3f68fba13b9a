"""Functional lifts of articulated objects: a bucket lifted by its bail handle."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco

from dexbench.assets import turned
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.articulation_turn import BAIL_REST, BUCKET_REGION
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan
from dexbench.tasks.templates import LiftTask, Placement


@register
class LiftBucket(LiftTask):
    name = "LiftBucket"
    category = "functional"
    instruction = "Pick up the bucket."
    description = ("Grasp an articulated bucket and lift the bucket body away from the "
                   "tabletop.")
    success_text = "The bucket is lifted at least 0.12 m above its spawn height."
    # GraspBucket's bucket and region: the bail lies towards the robot, 3 deg off its stop.
    placements: ClassVar = {"bucket": Placement(*BUCKET_REGION)}
    reset_joints: ClassVar = {"bucket/handle": -BAIL_REST + 0.05}
    lifted, lift_threshold = "bucket", 0.12
    focus_point = ("bucket", "grip")
    # The drawer's hook on the grip tube where it lies: the hand hangs between the robot
    # and the tube, palm towards the pail, the tube deep in the curled fingers (4.5 cm
    # further along them and 3.5 cm nearer the palm than a held cube); as the hand rises
    # the bail swings up in the hook and the pail follows.
    expert = GraspPlan("bucket", point=("grip", (0.011, 0.0, 0.0)), yaw="body",
                       yaw_offset=math.pi, pitch=math.pi / 2, shift=(0.045, 0.0, -0.035),
                       lift=0.2)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"bucket": turned.add_bucket(spec, "bucket", rest=BAIL_REST)}
