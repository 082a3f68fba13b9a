"""Lathe (surface-of-revolution) vessels: mugs and bottles built from a 2-D profile.

The visual mesh is the revolved profile. Collision geometry is convex by construction:
a closed convex vessel (bottle) collides as its own mesh (MuJoCo uses the convex hull);
an open vessel (mug) collides as a bottom disc plus a ring of thin wall boxes, an
explicit convex decomposition that lets things sit inside it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np

from dexbench.assets.objects import ObjectInfo, Zone, add_geom, free_body


def lathe_mesh(profile: Sequence[tuple[float, float]], segments: int = 32
               ) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (P*S, 3) and outward triangles of a profile (r, z) revolved about z.

    The profile runs from bottom to top; points with r = 0 are kept as rings of
    coincident vertices, which keeps the indexing uniform.
    """
    prof = np.asarray(profile, dtype=float)
    angles = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    verts = np.stack([np.outer(prof[:, 0], np.cos(angles)),
                      np.outer(prof[:, 0], np.sin(angles)),
                      np.repeat(prof[:, 1:2], segments, axis=1)], axis=-1).reshape(-1, 3)
    faces = []
    for i in range(len(prof) - 1):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            faces += [(a, b, d), (a, d, c)]
    return verts, np.array(faces, dtype=np.int32)


def _add_lathe_mesh(spec: mujoco.MjSpec, name: str, profile, segments: int) -> str:
    verts, faces = lathe_mesh(profile, segments)
    spec.add_mesh(name=name, uservert=verts.ravel().tolist(),
                  userface=faces.ravel().tolist())
    return name


def _open_vessel(spec: mujoco.MjSpec, name: str, radius: float, height: float, wall: float,
                 mass: float, pieces: int, rgba: Sequence[float]) -> mujoco.MjsBody:
    """A free open-topped cylinder: lathe visual, convex bottom disc and wall boxes."""
    body = free_body(spec, name)
    outer = [(0.0, 0.0), (radius * 0.92, 0.0), (radius, 0.01), (radius, height)]
    mesh = _add_lathe_mesh(spec, f"{name}/shell", outer, 32)
    body.add_geom(name=f"{name}/visual", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh,
                  rgba=list(rgba), contype=0, conaffinity=0, group=2, mass=0)
    bottom = 0.006
    add_geom(body, f"{name}/bottom", "cylinder", [radius - 0.002, bottom / 2], rgba,
             0.3 * mass, pos=[0, 0, bottom / 2])
    half_w = radius * math.tan(math.pi / pieces) + 1e-3
    for k in range(pieces):
        a = 2 * math.pi * k / pieces
        r = radius - wall / 2
        add_geom(body, f"{name}/wall{k}", "box", [wall / 2, half_w, height / 2], rgba,
                 0.5 * mass / pieces, pos=[r * math.cos(a), r * math.sin(a), height / 2],
                 quat=[math.cos(a / 2), 0, 0, math.sin(a / 2)])
    return body


def _vessel_info(name: str, radius: float, height: float, extra_points=None) -> ObjectInfo:
    rim = (0.0, 0.0, height)
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, radius + 0.02,
                      points={"rim": (name, rim), **(extra_points or {})},
                      axes={"up": (name, (0.0, 0.0, 1.0))},
                      zones=(Zone(name, "cylinder", rim, radius + 0.004, 0.008),))


def add_cup(spec: mujoco.MjSpec, name: str, radius: float = 0.035, height: float = 0.1,
            wall: float = 0.005, mass: float = 0.12, pieces: int = 16,
            rgba: Sequence[float] = (0.3, 0.6, 0.85, 1.0)) -> ObjectInfo:
    """An open cup without a handle; the rim is a do-not-touch zone."""
    _open_vessel(spec, name, radius, height, wall, mass, pieces, rgba)
    return _vessel_info(name, radius, height)


def add_mug(spec: mujoco.MjSpec, name: str, radius: float = 0.04, height: float = 0.095,
            wall: float = 0.006, mass: float = 0.25, pieces: int = 16,
            rgba: Sequence[float] = (0.85, 0.85, 0.9, 1.0)) -> ObjectInfo:
    """An open mug with a handle on its +x side; the rim is a do-not-touch zone."""
    body = _open_vessel(spec, name, radius, height, wall, mass, pieces, rgba)
    for k, (x, z, length) in enumerate(((radius + 0.012, 0.55 * height, 0.022),
                                        (radius + 0.004, 0.8 * height, 0.01),
                                        (radius + 0.004, 0.3 * height, 0.01))):
        quat = [1, 0, 0, 0] if k == 0 else [0.7071068, 0, 0.7071068, 0]
        add_geom(body, f"{name}/handle{k}", "capsule", [0.006, length], rgba,
                 0.2 * mass / 3, pos=[x, 0, z], quat=quat)
    handle = (radius + 0.012, 0.0, 0.55 * height)
    return _vessel_info(name, radius, height, {"handle": (name, handle)})


def _closed_vessel(spec: mujoco.MjSpec, name: str, profile, radius: float, height: float,
                   mass: float, rgba: Sequence[float]) -> ObjectInfo:
    """A free convex lathe solid that collides as its own (convex) mesh."""
    body = free_body(spec, name)
    mesh = _add_lathe_mesh(spec, f"{name}/shell", profile, 24)
    geom = body.add_geom(name=f"{name}/geom", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh,
                         rgba=list(rgba), condim=4, friction=[1.0, 0.005, 0.0001])
    geom.mass = mass
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, radius,
                      points={"centre": (name, (0.0, 0.0, height / 2)),
                              "top": (name, (0.0, 0.0, height))},
                      axes={"up": (name, (0.0, 0.0, 1.0))})


def add_bottle(spec: mujoco.MjSpec, name: str, radius: float = 0.03, height: float = 0.18,
               mass: float = 0.2, rgba: Sequence[float] = (0.2, 0.55, 0.35, 1.0)
               ) -> ObjectInfo:
    """A closed bottle: body, shoulder and neck; `centre` is mid-height."""
    neck = 0.012
    profile = [(0.0, 0.0), (radius * 0.95, 0.0), (radius, 0.008), (radius, 0.62 * height),
               (neck, 0.85 * height), (neck, height), (0.0, height)]
    return _closed_vessel(spec, name, profile, radius, height, mass, rgba)


def add_jar(spec: mujoco.MjSpec, name: str, radius: float = 0.045, height: float = 0.11,
            mass: float = 0.3, rgba: Sequence[float] = (0.75, 0.5, 0.3, 1.0)) -> ObjectInfo:
    """A closed jar with a lid rim: wide, short and convex."""
    profile = [(0.0, 0.0), (radius * 0.9, 0.0), (radius, 0.01), (radius, 0.8 * height),
               (0.85 * radius, 0.86 * height), (0.85 * radius, height), (0.0, height)]
    return _closed_vessel(spec, name, profile, radius, height, mass, rgba)
