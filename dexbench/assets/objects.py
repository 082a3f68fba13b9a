"""Procedural rigid objects built in code: nothing is loaded from disk.

Each builder adds one object to a scene spec at the origin (tasks place it at reset) and
returns its `ObjectInfo`: the root body, how it is held in place (free joint or mocap),
its resting height, footprint, joints, functional points and axes, and "do not touch"
zones. Sizes, masses and frictions are parameters.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

DEFAULT_FRICTION = (1.0, 0.005, 0.0001)
Vec3 = tuple[float, float, float]
UP: Vec3 = (0.0, 0.0, 1.0)
ALONG_X = [0.7071068, 0.0, 0.7071068, 0.0]  # turns a geom's z axis (capsule, cylinder) onto x


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


ROLLING_FRICTION = 0.002  # m: balls and capsules roll to a stop


def add_geom(body: mujoco.MjsBody, name: str, kind: str, size: Sequence[float],
             rgba: Sequence[float], mass: float | None = None,
             friction: Sequence[float] = DEFAULT_FRICTION, condim: int = 4,
             **kw) -> mujoco.MjsGeom:
    """A collision geom (condim 4 by default: torsional friction helps grasps)."""
    geom = body.add_geom(name=name, type=getattr(mujoco.mjtGeom, f"mjGEOM_{kind.upper()}"),
                         size=list(size), rgba=list(rgba), friction=list(friction),
                         condim=condim, **kw)
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
               rgba: Sequence[float] = (0.2, 0.4, 0.9, 1.0),
               friction: Sequence[float] = DEFAULT_FRICTION) -> ObjectInfo:
    """A free ball; its origin is its centre.

    It has rolling resistance (condim 6, 2 mm rolling friction, like a ball on a
    tablecloth) so a nudged ball comes to rest on the table instead of rolling off it.
    """
    body = free_body(spec, name)
    add_geom(body, f"{name}/geom", "sphere", [radius], rgba, mass,
             [*friction[:2], ROLLING_FRICTION], condim=6)
    return ObjectInfo(name, name, f"{name}/free", False, radius, radius)


def add_cylinder(spec: mujoco.MjSpec, name: str, radius: float = 0.025,
                 half_height: float = 0.035, mass: float = 0.1,
                 rgba: Sequence[float] = (0.9, 0.7, 0.1, 1.0),
                 friction: Sequence[float] = DEFAULT_FRICTION) -> ObjectInfo:
    """A free cylinder standing on one end; its origin is its centre."""
    body = free_body(spec, name)
    add_geom(body, f"{name}/geom", "cylinder", [radius, half_height], rgba, mass, friction)
    return ObjectInfo(name, name, f"{name}/free", False, half_height, radius,
                      axes={"up": (name, UP)})


def add_capsule(spec: mujoco.MjSpec, name: str, radius: float = 0.02,
                half_length: float = 0.03, mass: float = 0.1,
                rgba: Sequence[float] = (0.6, 0.2, 0.8, 1.0),
                friction: Sequence[float] = DEFAULT_FRICTION) -> ObjectInfo:
    """A free capsule lying along its x axis (standing on a round end is unstable).

    Like the ball it has rolling resistance (condim 6, `ROLLING_FRICTION`): without it a
    capsule set down on a flat top keeps rolling sideways at the speed it was let go with.
    """
    body = free_body(spec, name)
    add_geom(body, f"{name}/geom", "capsule", [radius, half_length], rgba, mass,
             [*friction[:2], ROLLING_FRICTION], condim=6, quat=ALONG_X)
    return ObjectInfo(name, name, f"{name}/free", False, radius, half_length + radius,
                      axes={"long": (name, (1.0, 0.0, 0.0))})


def add_stick(spec: mujoco.MjSpec, name: str, length: float = 0.15, radius: float = 0.015,
              mass: float = 0.1, upright: bool = True,
              foot_radius: float = 0.035) -> ObjectInfo:
    """A stick, by default standing upright on a flat foot (40% of its mass).

    PickUpStick needs the stick within 30 deg of vertical while lifted, so it starts
    upright; the foot keeps it standing. 0.15 m long by default, so its top (0.162 m)
    stays below a hand hovering 0.2 m above the table at reset. `upright=False`
    gives a footless capsule lying along x instead, which a hand must lift and turn.
    Axis `up` is the stick's length direction, the one that should point up when held;
    point `top` is its upper end when upright.
    """
    body = free_body(spec, name)
    wood = (0.85, 0.65, 0.3, 1.0)
    if not upright:
        add_geom(body, f"{name}/shaft", "capsule", [radius, length / 2 - radius], wood, mass,
                 quat=ALONG_X)
        return ObjectInfo(name, name, f"{name}/free", False, radius, length / 2,
                          points={"top": (name, (length / 2, 0.0, 0.0))},
                          axes={"up": (name, (1.0, 0.0, 0.0))})
    foot_h = 0.006
    add_geom(body, f"{name}/foot", "cylinder", [foot_radius, foot_h], (0.3, 0.3, 0.3, 1),
             0.4 * mass, pos=[0, 0, foot_h])
    add_geom(body, f"{name}/shaft", "cylinder", [radius, length / 2], wood, 0.6 * mass,
             pos=[0, 0, 2 * foot_h + length / 2])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, foot_radius,
                      points={"top": (name, (0.0, 0.0, 2 * foot_h + length))},
                      axes={"up": (name, UP)})


def add_goal_marker(spec: mujoco.MjSpec, name: str, radius: float = 0.02,
                    rgba: Sequence[float] = (0.1, 0.9, 0.2, 0.35)) -> ObjectInfo:
    """A translucent, non-colliding sphere shown at a goal point (mocap)."""
    body = mocap_body(spec, name)
    body.add_geom(name=f"{name}/geom", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius],
                  rgba=list(rgba), contype=0, conaffinity=0, group=2)
    return ObjectInfo(name, name, None, True, 0.0, 0.0)


PRIMITIVE_SHAPES: dict[str, Callable[[mujoco.MjSpec, str, float], ObjectInfo]] = {
    "box": lambda spec, name, mass: add_free_box(spec, name, (0.025, 0.025, 0.025), mass),
    "ball": lambda spec, name, mass: add_sphere(spec, name, 0.03, mass),
    "cylinder": lambda spec, name, mass: add_cylinder(spec, name, 0.025, 0.035, mass),
    "capsule": lambda spec, name, mass: add_capsule(spec, name, 0.02, 0.03, mass),
    "prism": lambda spec, name, mass: add_free_box(spec, name, (0.02, 0.045, 0.02), mass,
                                                   (0.1, 0.7, 0.6, 1.0)),
}


def add_primitive_set(spec: mujoco.MjSpec, names: Sequence[str],
                      mass: float = 0.08) -> dict[str, ObjectInfo]:
    """The candidate shapes of GraspTwoItems (keys of PRIMITIVE_SHAPES), each free."""
    return {name: PRIMITIVE_SHAPES[name](spec, name, mass) for name in names}


def add_tray(spec: mujoco.MjSpec, name: str, size: tuple[float, float] = (0.20, 0.14),
             mass: float = 0.5, rim: float = 0.025) -> ObjectInfo:
    """A flat tray (half extents `size`) with a low rim, lifted by two opposite sides.

    Points `grip_xpos` / `grip_xneg` are the middles of the short (+x / -x) rim walls,
    `grip_ypos` / `grip_yneg` those of the long (+y / -y) ones.
    """
    body = free_body(spec, name)
    hx, hy, t = size[0], size[1], 0.006
    color = (0.55, 0.4, 0.3, 1)
    add_geom(body, f"{name}/floor", "box", [hx, hy, t], color, 0.6 * mass, pos=[0, 0, t])
    for i, (px, py, sx, sy) in enumerate(((hx, 0, t, hy), (-hx, 0, t, hy),
                                          (0, hy, hx, t), (0, -hy, hx, t))):
        add_geom(body, f"{name}/rim{i}", "box", [sx, sy, rim / 2], color, 0.1 * mass,
                 pos=[px, py, 2 * t + rim / 2])
    grip_z = 2 * t + rim / 2
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, float(math.hypot(hx, hy)),
                      points={"grip_xpos": (name, (hx, 0.0, grip_z)),
                              "grip_xneg": (name, (-hx, 0.0, grip_z)),
                              "grip_ypos": (name, (0.0, hy, grip_z)),
                              "grip_yneg": (name, (0.0, -hy, grip_z))},
                      axes={"up": (name, UP)})


# PushT footprint: (centre x, centre y, half x, half y) in the T's body frame: a 0.20 x 0.05
# bar on top of a 0.05 x 0.15 stem, 0.03 thick.
T_SHAPE_RECTS = ((0.0, 0.075, 0.10, 0.025), (0.0, -0.025, 0.025, 0.075))
T_THICKNESS = 0.015  # half height


def t_shape_polygons(rects: Sequence[Sequence[float]] = T_SHAPE_RECTS) -> list[np.ndarray]:
    """The T's footprint as (4, 2) counter-clockwise polygons in its body frame.

    The pieces do not overlap, so the footprint area is the sum of theirs.
    """
    signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    return [np.array([cx, cy]) + signs * [hx, hy] for cx, cy, hx, hy in rects]


def add_t_shape(spec: mujoco.MjSpec, name: str, mass: float = 0.2,
                visual_only: bool = False) -> ObjectInfo:
    """The PushT block (free), or a flat non-colliding copy marking the goal (mocap)."""
    body = mocap_body(spec, name) if visual_only else free_body(spec, name)
    h = 0.001 if visual_only else T_THICKNESS
    rgba = (0.2, 0.8, 0.3, 0.4) if visual_only else (0.85, 0.3, 0.25, 1)
    areas = [hx * hy for _, _, hx, hy in T_SHAPE_RECTS]
    for i, (cx, cy, hx, hy) in enumerate(T_SHAPE_RECTS):
        kw = {"contype": 0, "conaffinity": 0, "group": 2} if visual_only else {}
        add_geom(body, f"{name}/part{i}", "box", [hx, hy, h], rgba,
                 None if visual_only else mass * areas[i] / sum(areas), pos=[cx, cy, 0], **kw)
    reach = max(float(np.linalg.norm(p, axis=1).max()) for p in t_shape_polygons())
    return ObjectInfo(name, name, None if visual_only else f"{name}/free", visual_only, h,
                      reach)


def add_peg(spec: mujoco.MjSpec, name: str, radius: float = 0.02, length: float = 0.12,
            mass: float = 0.1, grip_length: float = 0.03) -> ObjectInfo:
    """A cylindrical peg lying along its x axis, with a square grip block at its -x end.

    Point `head` is the +x end, the one inserted; `grip` the middle of the block, which
    is wider than the shaft (so it stops insertion) and flat-bottomed (so the peg does
    not roll). Axis `shaft` points from grip to head.
    """
    body = free_body(spec, name)
    add_geom(body, f"{name}/shaft", "cylinder", [radius, length / 2], (0.9, 0.6, 0.1, 1),
             0.75 * mass, quat=ALONG_X)
    grip = (-length / 2 - grip_length / 2, 0.0, 0.0)
    add_geom(body, f"{name}/grip", "box", [grip_length / 2, radius + 0.01, radius],
             (0.3, 0.3, 0.35, 1), 0.25 * mass, pos=list(grip))
    return ObjectInfo(name, name, f"{name}/free", False, radius, length / 2 + grip_length,
                      points={"head": (name, (length / 2, 0.0, 0.0)), "grip": (name, grip)},
                      axes={"shaft": (name, (1.0, 0.0, 0.0))})


def _frame_quat(x: np.ndarray, z: np.ndarray) -> list[float]:
    """Quaternion of the right-handed frame with unit axes x and z."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([x, np.cross(z, x), z]).ravel())
    return quat.tolist()


def add_hole_block(spec: mujoco.MjSpec, name: str, bore_radius: float = 0.023,
                   depth: float = 0.06, vertical: bool = False, axis_height: float = 0.08,
                   wall: float = 0.02, staves: int = 16) -> ObjectInfo:
    """A fixed (mocap) block with a round blind hole, built from convex pieces.

    The bore is a ring of `staves` boxes whose inner faces circumscribe `bore_radius`,
    closed at the far end by a cap. Horizontal (default): the bore runs along x at
    `axis_height` on a pedestal and opens on the -x face (towards the robot when
    unrotated). Vertical: the block stands on the table and the bore opens upwards.
    Points: `entrance` (centre of the opening), `target` (where a fully inserted peg head
    ends, 5 mm short of the bottom); axis `bore` points out of the hole.
    """
    body = mocap_body(spec, name)
    color = (0.45, 0.45, 0.5, 1)
    cap = 0.015
    if vertical:
        out, bottom = np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, cap])
        e1 = np.array([1.0, 0.0, 0.0])
    else:
        out, bottom = np.array([-1.0, 0.0, 0.0]), np.array([depth / 2, 0.0, axis_height])
        e1 = np.array([0.0, 0.0, 1.0])
        stand = axis_height - bore_radius
        add_geom(body, f"{name}/pedestal", "box", [depth / 2 + cap / 2, bore_radius + wall,
                                                   stand / 2], color,
                 pos=[cap / 2, 0, stand / 2])
    e2 = np.cross(out, e1)
    half_w = (bore_radius + wall) * math.tan(math.pi / staves)
    for k in range(staves):
        phi = 2 * math.pi * k / staves
        radial = math.cos(phi) * e1 + math.sin(phi) * e2
        pos = bottom + out * depth / 2 + radial * (bore_radius + wall / 2)
        add_geom(body, f"{name}/stave{k}", "box", [wall / 2, half_w, depth / 2], color,
                 pos=pos.tolist(), quat=_frame_quat(radial, out))
    cap_r = (bore_radius + wall) / math.cos(math.pi / staves)
    add_geom(body, f"{name}/cap", "cylinder", [cap_r, cap / 2], color,
             pos=(bottom - out * cap / 2).tolist(), quat=_frame_quat(e1, out))
    reach = cap_r if vertical else math.hypot(depth / 2 + cap, cap_r)
    entrance, target = bottom + out * depth, bottom + out * 0.005
    return ObjectInfo(name, name, None, True, 0.0, reach,
                      points={"target": (name, tuple(target.tolist())),
                              "entrance": (name, tuple(entrance.tolist()))},
                      axes={"bore": (name, tuple(out.tolist()))})
