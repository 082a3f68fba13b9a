"""Multi-goal composites: a primary articulated task plus a rigid add-on object.

A variant is two existing task definitions composed by `MultiGoalTask`; adding one is
a few lines, its expert a sequence of the two tasks' plans.
"""

from __future__ import annotations

import dataclasses

from dexbench.tasks.articulation import OpenDrawer
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import SequencePlan, Step
from dexbench.tasks.primitive import RelocateSphere
from dexbench.tasks.templates import MultiGoalTask, Placement

DRAWER_OPEN = 0.95  # of its travel: well past the task's threshold before letting go


@register
class OpenDrawerRelocateSphere(MultiGoalTask):
    name = "OpenDrawer_RelocateSphere"
    instruction = "Open the drawer and lift the ball."
    description = "Open the drawer and lift the sphere, both in one episode."
    success_text = ("At the same time: the drawer is open at least 80% of its travel and the "
                    "sphere is lifted at least 0.15 m above its reset height.")
    episode_seconds = 20.0
    primary_cls = OpenDrawer
    addon_cls = RelocateSphere
    addon_object = "sphere"
    # Beside the cabinet, clear of the drawer's travel (a ball in its way blocks it).
    addon_placement = Placement((-0.20, 0.0), (0.36, 0.46))
    # Open the drawer all the way and let go (it stays open), then lift the ball.
    expert = SequencePlan((
        Step(dataclasses.replace(OpenDrawer.expert, let_go=lambda e: (
            e.task.primary.joint_progress(e.view, OpenDrawer.joint) >= DRAWER_OPEN
        ).cpu().numpy())),
        Step(dataclasses.replace(RelocateSphere.expert, target=None))))
