"""Contact-rich fits: a gear onto its shaft, a charger plug into its socket."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import torch

from dexbench.assets import fasteners
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.contact_rich import lift_then_insert
from dexbench.tasks.plans import GraspPlan, InsertPlan
from dexbench.tasks.templates import Placement, TabletopTask


def _axial_lateral(view: SceneView, point: torch.Tensor, target: torch.Tensor,
                   axis: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Signed offset of `point` from `target` along unit `axis`, and its distance off it."""
    rel = point - target
    along = (rel * axis).sum(dim=1)
    return along, (rel - along[:, None] * axis).norm(dim=1)


# Grasped from above round its rim, lifted, lowered onto the shaft bore first and pushed
# down onto the column's seat; dropped or stalled, grasped again.
GEAR_PLAN = lift_then_insert(
    GraspPlan("gear", shift=(0.0, 0.0, 0.0), yaw="none", lift=0.1, settle=0.5),
    InsertPlan("gear", "base", head="hub", shaft="down", target="seat", bore="shaft"))


@register
class InsertGear(TabletopTask):
    name = "InsertGear"
    category = "contact_rich"
    instruction = "Put the gear onto the shaft of the gear base."
    description = ("Pick and place a gear onto the fixed gear base so that it seats into the "
                   "mesh position.")
    success_text = ("The gear's shaft point is centred within 0.0025 m of the base's shaft "
                    "and seated to within 0.003 m of full depth.")
    deviations = ("The paper gives no sizes or reset ranges: ours. The base holds one "
                  "shaft (the gear's mesh position) on a column; no second gear meshes "
                  "with it.",)
    placements: ClassVar = {
        "base": Placement((0.05, 0.15), (-0.15, 0.15), clearance=0.05),
        "gear": Placement((-0.15, -0.05), (-0.20, 0.20)),
    }
    centred, depth_tolerance = 0.0025, 0.003
    expert = GEAR_PLAN

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"gear": fasteners.add_gear(spec, "gear"),
                "base": fasteners.add_gear_base(spec, "base")}

    def _error(self, view: SceneView) -> tuple[torch.Tensor, torch.Tensor]:
        return _axial_lateral(view, self.point(view, "gear", "hub"),
                              self.point(view, "base", "seat"),
                              view.axis(*self.objects["base"].axes["shaft"]))

    def success(self, view: SceneView) -> torch.Tensor:
        along, lateral = self._error(view)
        return (along.abs() <= self.depth_tolerance) & (lateral <= self.centred)

    def progress(self, view: SceneView) -> torch.Tensor:
        along, lateral = self._error(view)
        return (1.0 - (along.abs() + lateral) / 0.5).clamp(min=0.0)


# Held from above over the brick's rear half, the fingers pointing back along it, away
# from the pin (pointing forward, they reach the socket before the pin is home); lifted a
# little, lined up with the receptacle and pushed in.
PLUG_PLAN = lift_then_insert(
    GraspPlan("plug", point="grip", shift=(0.0, 0.0, -0.005), yaw="body",
              yaw_offset=math.pi, lift=0.1, settle=0.5),
    InsertPlan("plug", "socket", head="tip", shaft="pin"))


@register
class PlugCharger(TabletopTask):
    name = "PlugCharger"
    category = "contact_rich"
    instruction = "Plug the charger into the socket."
    description = ("Align a charger plug with a fixed receptacle and insert the plug into the "
                   "socket.")
    success_text = ("The plug tip is inserted into the receptacle (at least 0.015 m of its "
                    "0.02 m pin past the opening: ours) with less than 0.0025 m of lateral "
                    "and vertical misalignment.")
    deviations = ("The paper gives no sizes, insertion depth or reset ranges: ours (a round "
                  "barrel pin in a receptacle 2 mm wider all round).",)
    placements: ClassVar = {
        "plug": Placement((-0.15, -0.05), (-0.20, 0.20)),
        "socket": Placement((0.10, 0.20), (-0.15, 0.15), (-0.3, 0.3), clearance=0.05),
    }
    inserted, misaligned = 0.015, 0.0025
    expert = PLUG_PLAN

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"plug": fasteners.add_charger_plug(spec, "plug"),
                "socket": fasteners.add_socket(spec, "socket")}

    def _errors(self, view: SceneView) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Depth of the tip past the socket's opening, and its horizontal and vertical
        offsets from the receptacle's axis."""
        out = view.axis(*self.objects["socket"].axes["bore"])
        rel = self.point(view, "plug", "tip") - self.point(view, "socket", "entrance")
        depth = -(rel * out).sum(dim=1)
        up = torch.zeros_like(out)
        up[:, 2] = 1.0
        side = torch.linalg.cross(out, up)
        side = side / side.norm(dim=1, keepdim=True)
        vertical = torch.linalg.cross(side, out)
        return depth, (rel * side).sum(dim=1).abs(), (rel * vertical).sum(dim=1).abs()

    def success(self, view: SceneView) -> torch.Tensor:
        depth, lateral, vertical = self._errors(view)
        return ((depth >= self.inserted) & (lateral < self.misaligned)
                & (vertical < self.misaligned))

    def progress(self, view: SceneView) -> torch.Tensor:
        depth, lateral, vertical = self._errors(view)
        miss = (self.inserted - depth).clamp(min=0.0) + lateral + vertical
        return (1.0 - miss / 0.5).clamp(min=0.0)
