"""Multi-goal composites: a primary articulated task plus a rigid add-on object.

A variant is two existing task definitions composed by `MultiGoalTask`; adding one is
four lines.
"""

from __future__ import annotations

from dexbench.tasks.articulation import OpenDrawer
from dexbench.tasks.primitive import RelocateSphere
from dexbench.tasks.templates import MultiGoalTask, Placement


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
