"""Meshes built in code: surfaces of revolution and their convex decomposition.

MuJoCo collides every mesh as its convex hull, so a hollow vessel given as one mesh would
be solid to anything dropped into it. `add_lathe_object` therefore keeps two sets of
geoms: the true revolved surface for rendering (group 2, massless, non-colliding) and
convex pieces for contact and inertia. Open vessels collide as a bottom slab plus a ring
of wall sectors; closed solids as a stack of convex lathe pieces, split wherever the
profile turns inward (a bottle's neck), so no piece's hull fills in a concavity.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import mujoco
import numpy as np

from dexbench.assets.objects import DEFAULT_FRICTION, free_body

Profile = Sequence[tuple[float, float]]  # (r, z) points, bottom to top


def lathe_mesh(profile: Profile, segments: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (P*S, 3) and outward triangles (2*(P-1)*S, 3) of a profile revolved about z.

    Traverse the profile counter-clockwise in the (r, z) half-plane (bottom, outside up,
    top) for outward normals. Points with r = 0 stay rings of coincident vertices, which
    keeps the indexing uniform; their zero-area triangles add no volume.
    """
    prof = np.asarray(profile, dtype=float)
    angles = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    verts = np.stack([np.outer(prof[:, 0], np.cos(angles)),
                      np.outer(prof[:, 0], np.sin(angles)),
                      np.repeat(prof[:, 1:2], segments, axis=1)], axis=-1).reshape(-1, 3)
    ring = np.arange(segments)
    a = (np.arange(len(prof) - 1)[:, None] * segments + ring).ravel()
    b = (np.arange(len(prof) - 1)[:, None] * segments + (ring + 1) % segments).ravel()
    faces = np.concatenate([np.stack([a, b, b + segments], 1),
                            np.stack([a, b + segments, a + segments], 1)])
    return verts, faces.astype(np.int32)


def loft_mesh(sections: Sequence[np.ndarray], heights: Sequence[float]
              ) -> tuple[np.ndarray, np.ndarray]:
    """A closed solid from (k, 2) counter-clockwise polygons stacked at rising heights.

    Corresponding vertices of neighbouring sections are joined and both ends are capped;
    with convex sections that scale or shift between levels the solid is convex.
    """
    k = len(sections[0])
    verts = np.concatenate([np.column_stack([np.asarray(s, float), np.full(k, h)])
                            for s, h in zip(sections, heights, strict=True)])
    faces = []
    for i in range(len(heights) - 1):
        for j in range(k):
            a, b = i * k + j, i * k + (j + 1) % k
            faces += [(a, b, b + k), (a, b + k, a + k)]
    top = (len(heights) - 1) * k
    faces += [(0, j + 1, j) for j in range(1, k - 1)]
    faces += [(top, top + j, top + j + 1) for j in range(1, k - 1)]
    return verts, np.array(faces, dtype=np.int32)


def mesh_volume(verts: np.ndarray, faces: np.ndarray) -> float:
    """Signed volume of a closed triangle mesh: positive iff its normals point outward."""
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def circle(radius: float, n: int) -> np.ndarray:
    """(n, 2) counter-clockwise regular polygon inscribed in a circle."""
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    return radius * np.column_stack([np.cos(t), np.sin(t)])


def sector(r_in: float, r_out: float, half_angle: float) -> np.ndarray:
    """(4, 2) counter-clockwise annulus sector (chords for arcs), centred on +x."""
    c, s = math.cos(half_angle), math.sin(half_angle)
    return np.array([[r_out * c, -r_out * s], [r_out * c, r_out * s],
                     [r_in * c, r_in * s], [r_in * c, -r_in * s]])


def radius_at(profile: Profile, z: float) -> float:
    """The profile's radius at height z (linear between points)."""
    prof = np.asarray(profile, dtype=float)
    return float(np.interp(z, prof[:, 1], prof[:, 0]))


def convex_runs(side: Profile) -> list[list[tuple[float, float]]]:
    """Split a side profile where it turns inward, so each run revolves to a convex solid.

    A solid of revolution is convex iff its radius is a concave function of height, i.e.
    the profile (bottom to top) only ever turns left; a right turn starts a new run.
    """
    pts = [tuple(map(float, p)) for p in side]
    runs, run = [], [pts[0]]
    for prev, cur, nxt in zip(pts, pts[1:], pts[2:], strict=False):
        run.append(cur)
        turn = (cur[0] - prev[0]) * (nxt[1] - cur[1]) - (cur[1] - prev[1]) * (nxt[0] - cur[0])
        if turn < -1e-12:
            runs.append(run)
            run = [cur]
    runs.append([*run, pts[-1]])
    return runs


def add_mesh(spec: mujoco.MjSpec, name: str, verts: np.ndarray, faces: np.ndarray) -> str:
    spec.add_mesh(name=name, uservert=verts.ravel().tolist(), userface=faces.ravel().tolist())
    return name


def _z_quat(angle: float) -> list[float]:
    return [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]


def add_lathe_object(spec: mujoco.MjSpec, name: str, outer_profile: Profile,
                     wall_thickness: float | None = None, mass: float = 0.2,
                     rgba: Sequence[float] = (0.8, 0.8, 0.85, 1.0),
                     bottom_thickness: float | None = None, segments: int = 32,
                     sectors: int = 16, friction: Sequence[float] = DEFAULT_FRICTION
                     ) -> mujoco.MjsBody:
    """A free body revolved from its outer side profile, bottom (z = 0) at the origin.

    `outer_profile` lists (r > 0, z) points from the bottom edge up to the top edge; both
    ends are flat. With `wall_thickness` the vessel is open at the top (mug, cup, jar):
    hollow, with a bottom `bottom_thickness` thick (default: the wall's), colliding as a
    bottom slab plus `sectors` wall pieces per profile segment. Without it the solid is
    closed (bottle). `mass` is spread over the collision pieces by volume.
    """
    side = [(float(r), float(z)) for r, z in outer_profile]
    body = free_body(spec, name)
    pieces: list[tuple[str, np.ndarray, np.ndarray, list[list[float]]]] = []
    if wall_thickness is None:
        shell = [(0.0, side[0][1]), *side, (0.0, side[-1][1])]
        for i, run in enumerate(convex_runs(side)):
            verts, faces = loft_mesh([circle(r, segments) for r, _ in run], [z for _, z in run])
            pieces.append((f"{name}/part{i}", verts, faces, [[1.0, 0.0, 0.0, 0.0]]))
    else:
        tb = wall_thickness if bottom_thickness is None else bottom_thickness
        levels = [tb] + [z for _, z in side if z > tb]
        inner = [(radius_at(side, z) - wall_thickness, z) for z in levels]
        shell = [(0.0, side[0][1]), *side, *inner[::-1], (0.0, tb)]
        base = [(r, z) for r, z in side if z < tb] + [(radius_at(side, tb), tb)]
        verts, faces = loft_mesh([circle(r, segments) for r, _ in base], [z for _, z in base])
        pieces.append((f"{name}/bottom", verts, faces, [[1.0, 0.0, 0.0, 0.0]]))
        half = math.pi / sectors
        turns = [_z_quat(2 * half * k) for k in range(sectors)]
        for i, (z0, z1) in enumerate(itertools.pairwise(levels)):
            rings = [sector(radius_at(side, z) - wall_thickness, radius_at(side, z), half)
                     for z in (z0, z1)]
            verts, faces = loft_mesh(rings, [z0, z1])
            pieces.append((f"{name}/wall{i}", verts, faces, turns))
    verts, faces = lathe_mesh(shell, segments)
    body.add_geom(name=f"{name}/visual", type=mujoco.mjtGeom.mjGEOM_MESH,
                  meshname=add_mesh(spec, f"{name}/visual", verts, faces), rgba=list(rgba),
                  contype=0, conaffinity=0, group=2, mass=0.0)
    total = sum(mesh_volume(v, f) * len(q) for _, v, f, q in pieces)
    for mesh, verts, faces, quats in pieces:
        add_mesh(spec, mesh, verts, faces)
        piece_mass = mass * mesh_volume(verts, faces) / total
        for k, quat in enumerate(quats):
            geom_name = mesh if len(quats) == 1 else f"{mesh}_{k}"
            body.add_geom(name=geom_name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh,
                          quat=quat, rgba=list(rgba), friction=list(friction), condim=4,
                          group=3, mass=piece_mass)
    return body
