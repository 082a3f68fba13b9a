"""Procedural rigid objects built in code: nothing is loaded from disk.

Each builder adds one object to a scene spec at the origin (tasks place it at reset) and
returns its `ObjectInfo`: the root body, how it is held in place (free joint or mocap),
its resting height, footprint, joints, functional points and axes, and "do not touch"
zones. Sizes, masses and frictions are parameters.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

DEFAULT_FRICTION = (1.0, 0.005, 0.0001)
Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Zone:
    """A volume hands must not touch (e.g. a mug rim), fixed in a body's frame."""

    body: str
    kind: str  # "sphere" | "cylinder"
    pos: Vec3
    radius: float
    half_length: float = 0.0  # cylinders: half extent along `axis`
    axis: Vec3 = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class ObjectInfo:
    """What a task needs to know about an object it built."""

    name: str
    root: str
    free_joint: str | None  # "<name>/free" for free objects
    mocap: bool  # fixed objects: the root is a mocap body placed per env at reset
    rest_height: float  # root height above the support when resting upright
    footprint_radius: float  # xy radius, for non-overlapping placement
    joints: dict[str, tuple[float, float]] = field(default_factory=dict)
    points: dict[str, tuple[str, Vec3]] = field(default_factory=dict)
    axes: dict[str, tuple[str, Vec3]] = field(default_factory=dict)
    zones: tuple[Zone, ...] = ()


def new_spec() -> mujoco.MjSpec:
    """A fresh spec whose angles are radians (MjSpec's default is degrees).

    Every spec dexbench creates comes from here, so joint ranges written in code mean
    radians everywhere; attached robot models keep their own files' settings.
    """
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    return spec


def free_body(spec: mujoco.MjSpec, name: str) -> mujoco.MjsBody:
    """A body with a free joint `<name>/free`."""
    body = spec.worldbody.add_body(name=name)
    body.add_freejoint(name=f"{name}/free")
    return body


def mocap_body(spec: mujoco.MjSpec, name: str) -> mujoco.MjsBody:
    """A fixed body whose pose a task sets per environment (mocap)."""
    return spec.worldbody.add_body(name=name, mocap=True)


def add_geom(body: mujoco.MjsBody, name: str, kind: str, size: Sequence[float],
             rgba: Sequence[float], mass: float | None = None,
             friction: Sequence[float] = DEFAULT_FRICTION, **kw) -> mujoco.MjsGeom:
    """A collision geom (condim 4: torsional friction helps grasps)."""
    geom = body.add_geom(name=name, type=getattr(mujoco.mjtGeom, f"mjGEOM_{kind.upper()}"),
                         size=list(size), rgba=list(rgba), friction=list(friction),
                         condim=4, **kw)
    if mass is not None:
        geom.mass = mass
    return geom


def add_free_box(spec: mujoco.MjSpec, name: str, half_size: Sequence[float], mass: float,
                 rgba: Sequence[float] = (0.8, 0.2, 0.2, 1.0),
                 friction: Sequence[float] = DEFAULT_FRICTION) -> ObjectInfo:
    """A free box resting on its bottom face."""
    body = free_body(spec, name)
    add_geom(body, f"{name}/geom", "box", half_size, rgba, mass, friction)
    return ObjectInfo(name, name, f"{name}/free", False, half_size[2],
                      float((half_size[0] ** 2 + half_size[1] ** 2) ** 0.5))


def add_sphere(spec: mujoco.MjSpec, name: str, radius: float = 0.03, mass: float = 0.1,
               rgba: Sequence[float] = (0.2, 0.4, 0.9, 1.0)) -> ObjectInfo:
    body = free_body(spec, name)
    add_geom(body, f"{name}/geom", "sphere", [radius], rgba, mass)
    return ObjectInfo(name, name, f"{name}/free", False, radius, radius)


def add_stick(spec: mujoco.MjSpec, name: str, length: float = 0.15, radius: float = 0.015,
              mass: float = 0.08, foot_radius: float = 0.035) -> ObjectInfo:
    """A stick standing upright on a small flat foot, so it rests stably at reset."""
    body = free_body(spec, name)
    foot_h = 0.006
    add_geom(body, f"{name}/foot", "cylinder", [foot_radius, foot_h], (0.3, 0.3, 0.3, 1),
             0.25 * mass, pos=[0, 0, foot_h])
    add_geom(body, f"{name}/shaft", "cylinder", [radius, length / 2],
             (0.85, 0.65, 0.3, 1), 0.75 * mass, pos=[0, 0, 2 * foot_h + length / 2])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, foot_radius,
                      points={"top": (name, (0.0, 0.0, 2 * foot_h + length))},
                      axes={"up": (name, (0.0, 0.0, 1.0))})


def add_goal_marker(spec: mujoco.MjSpec, name: str, radius: float = 0.02,
                    rgba: Sequence[float] = (0.1, 0.9, 0.2, 0.35)) -> ObjectInfo:
    """A translucent, non-colliding sphere shown at a goal point (mocap)."""
    body = mocap_body(spec, name)
    body.add_geom(name=f"{name}/geom", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius],
                  rgba=list(rgba), contype=0, conaffinity=0, group=2)
    return ObjectInfo(name, name, None, True, 0.0, 0.0)


PRIMITIVE_SHAPES = {
    "box": ("box", (0.025, 0.025, 0.025), (0.8, 0.2, 0.2, 1)),
    "ball": ("sphere", (0.03,), (0.2, 0.4, 0.9, 1)),
    "cylinder": ("cylinder", (0.025, 0.035), (0.9, 0.7, 0.1, 1)),
    "capsule": ("capsule", (0.02, 0.03), (0.6, 0.2, 0.8, 1)),
    "prism": ("box", (0.02, 0.045, 0.02), (0.1, 0.7, 0.6, 1)),
}


def add_primitive_set(spec: mujoco.MjSpec, names: Sequence[str],
                      mass: float = 0.08) -> dict[str, ObjectInfo]:
    """The candidate shapes of GraspTwoItems, each a free object."""
    out = {}
    for name in names:
        kind, size, rgba = PRIMITIVE_SHAPES[name]
        body = free_body(spec, name)
        add_geom(body, f"{name}/geom", kind, size, rgba, mass)
        rest = size[0] + size[1] if kind == "capsule" else size[-1]
        footprint = float(np.hypot(size[0], size[1]) if kind == "box" else size[0])
        out[name] = ObjectInfo(name, name, f"{name}/free", False, rest, footprint)
    return out


def add_tray(spec: mujoco.MjSpec, name: str, size: tuple[float, float] = (0.20, 0.14),
             mass: float = 0.5, rim: float = 0.025) -> ObjectInfo:
    """A flat tray with a low rim; lifted from its two short sides."""
    body = free_body(spec, name)
    hx, hy, t = size[0], size[1], 0.006
    color = (0.55, 0.4, 0.3, 1)
    add_geom(body, f"{name}/floor", "box", [hx, hy, t], color, 0.6 * mass, pos=[0, 0, t])
    for i, (px, py, sx, sy) in enumerate(((hx, 0, t, hy), (-hx, 0, t, hy),
                                          (0, hy, hx, t), (0, -hy, hx, t))):
        add_geom(body, f"{name}/rim{i}", "box", [sx, sy, rim / 2], color, 0.1 * mass,
                 pos=[px, py, 2 * t + rim / 2])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, float((hx**2 + hy**2) ** 0.5),
                      axes={"up": (name, (0.0, 0.0, 1.0))})


# PushT footprint: (centre x, centre y, half x, half y) in the T's body frame.
T_SHAPE_RECTS = ((0.0, 0.075, 0.10, 0.025), (0.0, -0.025, 0.025, 0.075))
T_THICKNESS = 0.015  # half height


def add_t_shape(spec: mujoco.MjSpec, name: str, mass: float = 0.2,
                visual_only: bool = False) -> ObjectInfo:
    """The PushT block (free), or a flat non-colliding copy marking the goal (mocap)."""
    body = mocap_body(spec, name) if visual_only else free_body(spec, name)
    h = 0.001 if visual_only else T_THICKNESS
    rgba = (0.2, 0.8, 0.3, 0.4) if visual_only else (0.85, 0.3, 0.25, 1)
    for i, (cx, cy, hx, hy) in enumerate(T_SHAPE_RECTS):
        kw = {"contype": 0, "conaffinity": 0, "group": 2} if visual_only else {}
        add_geom(body, f"{name}/part{i}", "box", [hx, hy, h], rgba,
                 None if visual_only else mass / 2, pos=[cx, cy, 0], **kw)
    return ObjectInfo(name, name, None if visual_only else f"{name}/free", visual_only, h,
                      0.11)


def add_peg(spec: mujoco.MjSpec, name: str, radius: float = 0.015, length: float = 0.12,
            mass: float = 0.08) -> ObjectInfo:
    """A cylindrical peg lying on the table along its x axis; `head` is its +x end."""
    body = free_body(spec, name)
    add_geom(body, f"{name}/shaft", "cylinder", [radius, length / 2], (0.9, 0.6, 0.1, 1),
             mass, quat=[0.7071068, 0, 0.7071068, 0])
    return ObjectInfo(name, name, f"{name}/free", False, radius, length / 2,
                      points={"head": (name, (length / 2, 0.0, 0.0))},
                      axes={"shaft": (name, (1.0, 0.0, 0.0))})


def add_hole_block(spec: mujoco.MjSpec, name: str, bore_radius: float = 0.023,
                   depth: float = 0.06, height: float = 0.12) -> ObjectInfo:
    """A fixed block with a horizontal square-section bore along its local -x axis.

    The bore opens on the -x face (towards the robot when unrotated); `target` is the
    point a fully inserted peg head reaches, `bore` the axis pointing out of the hole.
    """
    body = mocap_body(spec, name)
    wall, half_w = 0.03, bore_radius + 0.03
    zc = height / 2
    color = (0.45, 0.45, 0.5, 1)
    add_geom(body, f"{name}/top", "box", [depth / 2, half_w, (zc - bore_radius) / 2],
             color, pos=[0, 0, zc + bore_radius + (zc - bore_radius) / 2])
    add_geom(body, f"{name}/bottom", "box", [depth / 2, half_w, (zc - bore_radius) / 2],
             color, pos=[0, 0, (zc - bore_radius) / 2])
    for i, sy in enumerate((1, -1)):
        add_geom(body, f"{name}/side{i}", "box", [depth / 2, wall / 2, bore_radius], color,
                 pos=[0, sy * (bore_radius + wall / 2), zc])
    add_geom(body, f"{name}/back", "box", [0.01, half_w, zc], color,
             pos=[depth / 2 + 0.01, 0, zc])
    target = (depth / 2 - 0.005, 0.0, zc)
    return ObjectInfo(name, name, None, True, 0.0, 0.07,
                      points={"target": (name, target), "entrance": (name, (-depth / 2, 0, zc))},
                      axes={"bore": (name, (-1.0, 0.0, 0.0))})
