"""Contact-rich precision: insert, plug, thread under sustained contact."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import objects, office
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import (
    GraspPlan,
    InsertPlan,
    PinchPlan,
    SequencePlan,
    Step,
    body_yaw,
    turnable_offset,
)
from dexbench.tasks.templates import Placement, TabletopTask

PEG_RAISED = 0.03  # m: the held peg is clear of the table, the hand may turn it
PEG_DROPPED = 0.015  # m: back on the table (or stalled lining up), it is grasped again


def _hole_yaw(env) -> np.ndarray:
    return body_yaw(env.view.body_quat("hole").cpu().numpy())


def lift_then_insert(take: GraspPlan | PinchPlan, insert: InsertPlan,
                     raised: float = PEG_RAISED) -> SequencePlan:
    """Pick the part up (`take`), lift it above `raised` (m), then `insert` it; dropped
    back onto the table or stalled lining up, pick it up again."""
    obj = take.obj
    return SequencePlan((
        Step(take, until=lambda e, held: held.carrying & (
            e.task.lift(e.view, obj).cpu().numpy() > raised)),
        Step(insert)),
        restart=lambda e, experts: (e.task.lift(e.view, obj) < PEG_DROPPED).cpu().numpy()
        | experts[1].stalled)


# Across the shaft, near the grip end: the hand's width leaves the head free to go in.
# Held, lifted a little, then inserted; dropped or stalled, grasped again.
PEG_PLAN = lift_then_insert(
    GraspPlan("peg", point=("grip", (0.04, 0.0, 0.0)), shift=(0.0, 0.0, -0.005), yaw="body",
              yaw_offset=turnable_offset("peg", _hole_yaw, (math.pi / 2, -math.pi / 2)),
              lift=0.1, settle=0.5),
    InsertPlan("peg", "hole"))


@register
class InsertPeg(TabletopTask):
    name = "InsertPeg"
    category = "contact_rich"
    instruction = "Insert the peg into the hole."
    description = "Align a side peg with a fixed tabletop hole and insert it into the opening."
    success_text = ("The peg head is inserted to within 0.015 m along the axis and stays "
                    "within the hole's 0.023 m bore radius laterally.")
    placements: ClassVar = {
        "peg": Placement((-0.15, -0.05), (-0.20, 0.20)),
        "hole": Placement((0.10, 0.20), (-0.15, 0.15), (-0.3, 0.3), clearance=0.05),
    }
    depth_tolerance, bore_radius = 0.015, 0.023
    expert = PEG_PLAN

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"peg": objects.add_peg(spec, "peg"),
                "hole": objects.add_hole_block(spec, "hole", bore_radius=self.bore_radius)}

    def _error(self, view: SceneView) -> tuple[torch.Tensor, torch.Tensor]:
        """Axial and lateral offset of the peg head from the hole's insertion target."""
        head = view.point_pos(*self.objects["peg"].points["head"])
        target = view.point_pos(*self.objects["hole"].points["target"])
        axis = view.axis(*self.objects["hole"].axes["bore"])
        rel = head - target
        along = (rel * axis).sum(dim=1)
        lateral = (rel - along[:, None] * axis).norm(dim=1)
        return along.abs(), lateral

    def success(self, view: SceneView) -> torch.Tensor:
        along, lateral = self._error(view)
        return (along <= self.depth_tolerance) & (lateral <= self.bore_radius)

    def progress(self, view: SceneView) -> torch.Tensor:
        along, lateral = self._error(view)
        return 1.0 - (along + lateral) / 0.5


PEN_RAISED = 0.2  # m: high enough for the pen, turned tip-down, to clear the holder


# Pinched between the thumb and index tips across the barrel, nearer the clip end so the
# tip hangs well below the hand once turned down (the thumb rises as it closes: the tips
# are levelled where they nearly meet, at the barrel's sides); lifted, then turned
# tip-down over the holder and lowered in.
def pinch_and_insert(obj: str, hole: str, point: tuple, raised: float) -> SequencePlan:
    """Pinch a slender `obj` across its barrel at `point`, lift it above `raised` (m),
    turn it tip-down over `hole` and lower it in; dropped or stalled, pinch it again."""
    return lift_then_insert(
        PinchPlan(obj, point=point, depth=0.004, lift=0.25, level=0.85, hangs=True),
        InsertPlan(obj, hole, head="tip", shaft="long", synergy="tip_pinch"), raised)


PEN_PLAN = pinch_and_insert("pen", "holder", ("tail", (0.05, 0.0, 0.0)), PEN_RAISED)


class SlenderInsertTask(TabletopTask):
    """A slender object put end first into an opening: success while one of its `ends`
    is centred within `centred` (m, horizontally) of the `holder`'s "entrance" point and
    at least `below` (m) under it."""

    slender: ClassVar[str]
    holder: ClassVar[str]
    ends: ClassVar[tuple[str, ...]]
    centred: ClassVar[float]
    below: ClassVar[float]

    def _errors(self, view: SceneView) -> tuple[torch.Tensor, torch.Tensor]:
        """(N, E) horizontal offset from the opening and depth below the rim of each end."""
        ends = torch.stack([self.point(view, self.slender, end) for end in self.ends], dim=1)
        rel = ends - self.point(view, self.holder, "entrance")[:, None]
        return rel[..., :2].norm(dim=-1), -rel[..., 2]

    def success(self, view: SceneView) -> torch.Tensor:
        off, depth = self._errors(view)
        return ((off <= self.centred) & (depth >= self.below)).any(dim=1)

    def progress(self, view: SceneView) -> torch.Tensor:
        off, depth = self._errors(view)
        return (1.0 - off / 0.5 - (self.below - depth).clamp(min=0.0) / 0.2).max(dim=1).values


@register
class InsertPen(SlenderInsertTask):
    name = "InsertPen"
    category = "contact_rich"
    instruction = "Put the pen into the pen holder."
    description = "Pick up a pen and guide either tip into the opening of a pen holder."
    success_text = ("Either pen tip is centred within 0.038 m (horizontally) of the holder "
                    "opening and at least 0.03 m below its rim.")
    episode_seconds = 25.0
    deviations = ("The authors give x ranges only: the pen's and the holder's y ranges "
                  "(-0.15..0.15) are ours.",)
    placements: ClassVar = {
        "pen": Placement((-0.30, -0.20), (-0.15, 0.15)),
        "holder": Placement((0.15, 0.20), (-0.15, 0.15), clearance=0.05),
    }
    centred, below = 0.038, 0.03
    expert = PEN_PLAN
    slender, holder, ends = "pen", "holder", ("tip", "tail")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"pen": office.add_pen(spec, "pen"), "holder": office.add_pen_holder(spec, "holder")}
