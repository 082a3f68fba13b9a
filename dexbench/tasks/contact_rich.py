"""Contact-rich precision: insert, plug, thread under sustained contact."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import objects
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import (
    GraspPlan,
    InsertPlan,
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


# Across the shaft, near the grip end: the hand's width leaves the head free to go in.
# Held, lifted a little, then inserted; dropped or stalled, grasped again.
PEG_PLAN = SequencePlan((
    Step(GraspPlan("peg", point=("grip", (0.04, 0.0, 0.0)), shift=(0.0, 0.0, -0.005), yaw="body",
                   yaw_offset=turnable_offset("peg", _hole_yaw, (math.pi / 2, -math.pi / 2)),
                   lift=0.1, settle=0.5),
         until=lambda e, grasp: grasp.carrying & (
             e.task.lift(e.view, "peg").cpu().numpy() > PEG_RAISED)),
    Step(InsertPlan("peg", "hole"))),
    restart=lambda e, experts: (e.task.lift(e.view, "peg") < PEG_DROPPED).cpu().numpy()
    | experts[1].stalled)


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
