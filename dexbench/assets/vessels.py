"""Pouring vessels with a spout or lip a hand must keep off: soup can, bleach, kettle.

Each stands upright with its bottom at the body origin (`rest_height` 0); axis `up` is
its vertical. The geoms of the no-touch part (lip, nozzle, spout) live in their own
jointless child body, which is the body of the object's `Zone` (see `parts`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np

from dexbench.assets.meshes import add_lathe_object, add_mesh, circle, loft_mesh, sector
from dexbench.assets.objects import UP, ObjectInfo, Zone, add_geom, free_body
from dexbench.assets.parts import add_visual, zone_body

STEEL = (0.72, 0.74, 0.78, 1.0)
BLACK = (0.12, 0.12, 0.13, 1.0)


def ring_zone(spec: mujoco.MjSpec, parent: mujoco.MjsBody, name: str, z: float,
              radii: tuple[tuple[float, float], tuple[float, float]], height: float,
              mass: float, rgba: Sequence[float], sectors: int = 16) -> mujoco.MjsBody:
    """A no-touch band round a vessel's opening (a can's lip, a cup's rim): the zone body
    `name`, `z` up `parent`'s axis, holding a ring of `sectors` convex pieces `height`
    tall whose (inner, outer) radii go from `radii[0]` at its foot to `radii[1]` at its
    top (a conical wall's band continues the wall below it)."""
    body = zone_body(parent, name, (0.0, 0.0, z))
    half = math.pi / sectors
    rings = [sector(inner, outer, half) for inner, outer in radii]
    mesh = add_mesh(spec, name, *loft_mesh(rings, [0.0, height]))
    for k in range(sectors):
        turn = [math.cos(half * k), 0.0, 0.0, math.sin(half * k)]
        body.add_geom(name=f"{name}{k}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh,
                      quat=turn, rgba=list(rgba), condim=4, mass=mass / sectors)
    return body


def add_can(spec: mujoco.MjSpec, name: str, radius: float = 0.033, height: float = 0.10,
            wall: float = 0.003, mass: float = 0.12,
            label: Sequence[float] = (0.75, 0.12, 0.1, 1.0)) -> ObjectInfo:
    """An opened soup can: a thin-walled open cylinder whose rolled lip is the no-touch part.

    The lip is a ring of 16 convex pieces (body `<name>/lip`, 10% of the mass) on top of
    the wall. Points: `lip` (centre of the opening, the pour point), `bottom`.
    """
    lip_h = 0.004
    body = add_lathe_object(spec, name, [(0.95 * radius, 0.0), (radius, 0.005),
                                         (radius, height)], wall, 0.9 * mass, STEEL,
                            bottom_thickness=0.004)
    add_visual(body, f"{name}/label", "cylinder", [radius + 5e-4, 0.35 * height], label,
            pos=[0, 0, 0.5 * height])
    ring = (radius - wall, radius + 0.001)
    ring_zone(spec, body, f"{name}/lip", height, (ring, ring), lip_h, 0.1 * mass, STEEL)
    top = (0.0, 0.0, height + lip_h)
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, radius + 0.001,
                      points={"lip": (name, top), "bottom": (name, (0.0, 0.0, 0.0))},
                      axes={"up": (name, UP)},
                      zones=(Zone(f"{name}/lip", "cylinder", (0.0, 0.0, lip_h),
                                  radius + 0.005, 0.01),))


def _rounded_rect(hx: float, hy: float, r: float, per_corner: int = 6) -> np.ndarray:
    """(4 * per_corner, 2) counter-clockwise rectangle with rounded corners."""
    pts = []
    for k, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        for t in np.linspace(0.0, math.pi / 2, per_corner):
            a = math.pi / 2 * k + t
            pts.append((sx * (hx - r) + r * math.cos(a), sy * (hy - r) + r * math.sin(a)))
    return np.array(pts)


def add_bleach_bottle(spec: mujoco.MjSpec, name: str, mass: float = 0.4,
                      rgba: Sequence[float] = (0.95, 0.95, 0.9, 1.0)) -> ObjectInfo:
    """A bleach jug (0.10 x 0.07 x 0.26 m): handle loop at the back (-x), nozzle at front.

    The body and shoulder are convex meshes; the handle is a capsule bar 2.5 cm behind
    the wall (room for fingers) on two arms. The cap (body `<name>/nozzle`) is the
    no-touch part. Points: `nozzle` (top of the cap, the pour point), `handle` (middle of
    the bar), `centre`.
    """
    hx, hy, wall_top, neck_x = 0.05, 0.035, 0.17, 0.02
    body = free_body(spec, name)
    side = _rounded_rect(hx, hy, 0.02)
    verts, faces = loft_mesh([0.95 * side, side, side], [0.0, 0.006, wall_top])
    add_geom(body, f"{name}/body", "mesh", [0.0], rgba, 0.78 * mass,
             meshname=add_mesh(spec, f"{name}/body", verts, faces))
    neck = circle(0.018, len(side)) + [neck_x, 0.0]
    verts, faces = loft_mesh([side, neck], [wall_top, 0.215])
    add_geom(body, f"{name}/shoulder", "mesh", [0.0], rgba, 0.1 * mass,
             meshname=add_mesh(spec, f"{name}/shoulder", verts, faces))
    add_geom(body, f"{name}/neck", "cylinder", [0.016, 0.01], rgba, 0.02 * mass,
             pos=[neck_x, 0, 0.222])
    bar_x, low, high, bar_r = -hx - 0.025 - 0.011, 0.11, 0.185, 0.011
    for k, (a, b) in enumerate((((bar_x, 0, low), (bar_x, 0, high)),
                                ((-hx + 0.005, 0, low), (bar_x, 0, low)),
                                ((-0.04, 0, high), (bar_x, 0, high)))):
        add_geom(body, f"{name}/handle{k}", "capsule", [bar_r], rgba, 0.03 * mass,
                 fromto=[*a, *b])
    nozzle = zone_body(body, f"{name}/nozzle", (neck_x, 0.0, 0.232))
    add_geom(nozzle, f"{name}/cap", "cylinder", [0.02, 0.012], (0.2, 0.35, 0.8, 1.0),
             0.01 * mass, pos=[0, 0, 0.012])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, -bar_x + bar_r,
                      points={"nozzle": (f"{name}/nozzle", (0.0, 0.0, 0.024)),
                              "handle": (name, (bar_x, 0.0, (low + high) / 2)),
                              "centre": (name, (0.0, 0.0, wall_top / 2))},
                      axes={"up": (name, UP)},
                      zones=(Zone(f"{name}/nozzle", "cylinder", (0.0, 0.0, 0.012), 0.025,
                                  0.017),))


def add_kettle(spec: mujoco.MjSpec, name: str, mass: float = 0.6) -> ObjectInfo:
    """A kettle (radius 0.068, 0.16 m tall) with a side handle at -x and a spout at +x.

    The body is a closed solid of revolution; the handle bar stands 2.6 cm or more off
    the wall. The spout (body `<name>/spout`, a capsule rising at 45 deg) is the no-touch
    part. Points: `spout` (its tip), `handle` (middle of the bar), `lid` (knob top).
    Axes: `up`, `spout` (the direction the spout points).
    """
    profile = [(0.062, 0.0), (0.068, 0.008), (0.068, 0.07), (0.058, 0.13), (0.045, 0.15)]
    body = add_lathe_object(spec, name, profile, None, 0.83 * mass, STEEL)
    add_geom(body, f"{name}/knob", "cylinder", [0.012, 0.008], BLACK, 0.02 * mass,
             pos=[0, 0, 0.158])
    bar_x, low, high, bar_r = -0.105, 0.035, 0.125, 0.011
    for k, (a, b) in enumerate((((bar_x, 0, low), (bar_x, 0, high)),
                                ((-0.06, 0, low), (bar_x, 0, low)),
                                ((-0.05, 0, high), (bar_x, 0, high)))):
        add_geom(body, f"{name}/handle{k}", "capsule", [bar_r], BLACK, 0.03 * mass,
                 fromto=[*a, *b])
    spout = zone_body(body, f"{name}/spout", (0.05, 0.0, 0.06))
    length, r = 0.06 * math.sqrt(2), 0.011
    add_geom(spout, f"{name}/spout", "capsule", [r], STEEL, 0.06 * mass,
             fromto=[0, 0, 0, 0.06, 0, 0.06])
    d = math.sqrt(0.5)
    tip = (0.06 + r * d, 0.0, 0.06 + r * d)
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, 0.05 + 0.06 + r,
                      points={"spout": (f"{name}/spout", tip),
                              "handle": (name, (bar_x, 0.0, (low + high) / 2)),
                              "lid": (name, (0.0, 0.0, 0.166))},
                      axes={"up": (name, UP), "spout": (f"{name}/spout", (d, 0.0, d))},
                      zones=(Zone(f"{name}/spout", "cylinder", (0.03, 0.0, 0.03), r + 0.005,
                                  length / 2 + r, (d, 0.0, d)),))
