"""Stemmed glassware: a wine glass (foot, thin stem, open bowl) whose rim is no-touch.

Built like the other vessels (`meshes`): convex collision pieces carry the mass, a
massless revolved surface renders it. The glass stands upright with its foot's bottom at
the body origin (`rest_height` 0); axis `up` is its vertical.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np

from dexbench.assets.meshes import (
    add_mesh,
    circle,
    convex_runs,
    lathe_mesh,
    loft_mesh,
    mesh_volume,
    radius_at,
    sector,
)
from dexbench.assets.objects import DEFAULT_FRICTION, UP, ObjectInfo, Zone, free_body
from dexbench.assets.parts import zone_body

GLASS = (0.82, 0.9, 0.95, 0.55)
# A red-wine glass, 0.20 m tall (r, z): a 7.4 cm foot, a 9 mm stem up to 8.5 cm, and a
# bowl widest (8.6 cm) at 13 cm, narrowing to a 7 cm opening.
FOOT = ((0.037, 0.0), (0.036, 0.004), (0.008, 0.010))
STEM_RADIUS, STEM_TOP = 0.0045, 0.085
BOWL = ((0.006, 0.085), (0.020, 0.090), (0.032, 0.100), (0.040, 0.115), (0.043, 0.130),
        (0.042, 0.150), (0.039, 0.170), (0.035, 0.200))


def _revolved(side: Sequence[tuple[float, float]], segments: int = 32,
              ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Convex solids of revolution (vertices, faces) filling a side profile."""
    return [loft_mesh([circle(r, segments) for r, _ in run], [z for _, z in run])
            for run in convex_runs(side)]


def add_wine_glass(spec: mujoco.MjSpec, name: str, mass: float = 0.17, wall: float = 0.003,
                   floor: float = 0.008, band: float = 0.01, sectors: int = 16,
                   rgba: Sequence[float] = GLASS) -> ObjectInfo:
    """A wine glass of uniform glass, `mass` kg (a real one weighs 0.15-0.2 kg).

    The bowl's wall is `wall` thick, its solid bottom `floor` thick above the stem; the
    wall's top `band` (m) is the no-touch opening, its own ring of pieces in the zone
    body `<name>/rim`. Points: `rim` (centre of the opening), `bowl` (on the axis at the
    bowl's widest), `stem` (the stem's middle), `bottom`.
    """
    body = free_body(spec, name)
    top = BOWL[-1][1]
    below = top - band
    inside = BOWL[0][1] + floor
    half = math.pi / sectors
    turns = [[math.cos(half * k), 0.0, 0.0, math.sin(half * k)] for k in range(sectors)]
    # (mesh name, vertices, faces, orientations, parent body)
    pieces: list[tuple[str, np.ndarray, np.ndarray, list[list[float]], mujoco.MjsBody]] = []
    for i, (verts, faces) in enumerate(_revolved(FOOT)):
        pieces.append((f"{name}/foot{i}", verts, faces, [[1.0, 0.0, 0.0, 0.0]], body))
    stem = [(STEM_RADIUS, FOOT[-1][1] - 0.001), (STEM_RADIUS, STEM_TOP + 0.001)]
    verts, faces = loft_mesh([circle(r, 12) for r, _ in stem], [z for _, z in stem])
    pieces.append((f"{name}/stem", verts, faces, [[1.0, 0.0, 0.0, 0.0]], body))
    base = [p for p in BOWL if p[1] < inside] + [(radius_at(BOWL, inside), inside)]
    for i, (verts, faces) in enumerate(_revolved(base)):
        pieces.append((f"{name}/floor{i}", verts, faces, [[1.0, 0.0, 0.0, 0.0]], body))
    levels = [inside, *[z for _, z in BOWL if inside < z < below], below]
    for i in range(len(levels) - 1):
        z0, z1 = levels[i], levels[i + 1]
        rings = [sector(radius_at(BOWL, z) - wall, radius_at(BOWL, z), half) for z in (z0, z1)]
        verts, faces = loft_mesh(rings, [z0, z1])
        pieces.append((f"{name}/wall{i}", verts, faces, turns, body))
    rim = zone_body(body, f"{name}/rim", (0.0, 0.0, below))
    rings = [sector(radius_at(BOWL, z) - wall, radius_at(BOWL, z), half) for z in (below, top)]
    verts, faces = loft_mesh(rings, [0.0, band])
    pieces.append((f"{name}/rim", verts, faces, turns, rim))
    total = sum(mesh_volume(v, f) * len(q) for _, v, f, q, _ in pieces)
    for mesh, verts, faces, quats, parent in pieces:
        add_mesh(spec, mesh, verts, faces)
        for k, quat in enumerate(quats):
            parent.add_geom(name=mesh if len(quats) == 1 else f"{mesh}_{k}",
                            type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh, quat=quat,
                            rgba=list(rgba), friction=list(DEFAULT_FRICTION), condim=4,
                            group=3, mass=mass * mesh_volume(verts, faces) / total)
    outer = [*FOOT, (STEM_RADIUS, FOOT[-1][1]), (STEM_RADIUS, STEM_TOP), *BOWL[1:]]
    inner = [(radius_at(BOWL, z) - wall, z) for _, z in BOWL if z > inside][::-1]
    shell = [(0.0, 0.0), *outer, *inner, (radius_at(BOWL, inside) - wall, inside),
             (0.0, inside)]
    verts, faces = lathe_mesh(shell)
    body.add_geom(name=f"{name}/visual", type=mujoco.mjtGeom.mjGEOM_MESH,
                  meshname=add_mesh(spec, f"{name}/visual", verts, faces), rgba=list(rgba),
                  contype=0, conaffinity=0, group=2, mass=0.0)
    widest = max(BOWL)
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, widest[0],
                      points={"rim": (name, (0.0, 0.0, top)),
                              "bowl": (name, (0.0, 0.0, widest[1])),
                              "stem": (name, (0.0, 0.0, (FOOT[-1][1] + STEM_TOP) / 2)),
                              "bottom": (name, (0.0, 0.0, 0.0))},
                      axes={"up": (name, UP)},
                      zones=(Zone(f"{name}/rim", "cylinder", (0.0, 0.0, band / 2),
                                  BOWL[-1][0] + 0.005, band / 2 + 0.003),))
