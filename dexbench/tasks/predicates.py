"""Small batched predicates shared by task success conditions (torch, any device).

Definitions follow the paper and the authors' code: lift is height above the reset
height; tilt is the angle between an object axis and world z; articulation progress is
|q - q0| / max(q0 - lo, hi - q0), the fraction of the travel reachable from the reset
value.
"""

from __future__ import annotations

import math

import torch

from dexbench.assets.objects import Zone
from dexbench.envs.task_api import SceneView


def lift(view: SceneView, body: str) -> torch.Tensor:
    """(N,) height of a tracked body above its height at reset."""
    return view.body_pos(body)[:, 2] - view.initial_body_pos[body][:, 2]


def tilt_deg(axis_world: torch.Tensor) -> torch.Tensor:
    """(N,) angle in degrees between world directions (N, 3) and world +z."""
    cos = (axis_world[:, 2] / axis_world.norm(dim=1)).clamp(-1.0, 1.0)
    return torch.rad2deg(torch.arccos(cos))


def progress(q: torch.Tensor, q0: float, lo: float, hi: float) -> torch.Tensor:
    """(N,) fraction of the travel reachable from q0 that the joint has covered."""
    return (q - q0).abs() / max(q0 - lo, hi - q0)


def xy_dist(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """(N,) horizontal distance between points (N, 3)."""
    return (a[:, :2] - b[:, :2]).norm(dim=1)


def dist(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """(N,) distance between points (N, 3)."""
    return (a - b).norm(dim=1)


def zone_touched(view: SceneView, zone: Zone) -> torch.Tensor:
    """(N,) True where a hand touches the object inside a "do not touch" zone: a contact
    between any hand geom and the zone's body whose contact point lies in the zone."""
    found, pos = view.zone_contacts(zone)
    rel = pos - view.point_pos(zone.body, zone.pos)[:, None]
    if zone.kind == "sphere":
        inside = rel.norm(dim=-1) <= zone.radius
    else:
        axis = view.axis(zone.body, zone.axis)[:, None]
        along = (rel * axis).sum(dim=-1)
        radial = (rel - along[..., None] * axis).norm(dim=-1)
        inside = (along.abs() <= zone.half_length) & (radial <= zone.radius)
    return (found & inside).any(dim=1)


def deg(value: float) -> float:
    """Degrees to radians, for thresholds written as in the paper."""
    return math.radians(value)
