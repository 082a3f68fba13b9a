"""Lab and clutter objects: a dropper pipette and an Erlenmeyer flask, a corral of
primitive distractors, and a thin plate standing in a small slotted container.

Hollow parts (the flask, the container) are rings of convex staves, like
`objects.add_hole_block`, so a held object goes into a real opening. The fixed ones are
mocap bodies placed per env at reset (a clamped flask, a container fixed to the table).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np

from dexbench.assets.objects import (
    ALONG_X,
    DEFAULT_FRICTION,
    ROLLING_FRICTION,
    UP,
    ObjectInfo,
    Vec3,
    add_cylinder,
    add_free_box,
    add_geom,
    add_sphere,
    free_body,
    mocap_body,
)

GLASS = (0.82, 0.9, 0.95, 0.6)
RUBBER = (0.85, 0.25, 0.2, 1.0)
WOOD = (0.65, 0.5, 0.35, 1.0)
GREEN = (0.1, 0.8, 0.2, 1.0)
# Distractor colours: none of them green, so "the green object" names only the target.
DISTRACTOR_COLOURS = ((0.85, 0.2, 0.2, 1.0), (0.2, 0.35, 0.85, 1.0), (0.9, 0.75, 0.1, 1.0),
                      (0.6, 0.25, 0.7, 1.0), (0.9, 0.5, 0.15, 1.0))


def _stave_quat(radial: np.ndarray, along: np.ndarray) -> list[float]:
    """Quaternion of the frame whose x axis is `radial` and z axis `along` (unit, normal)."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([radial, np.cross(along, radial), along]).ravel())
    return quat.tolist()


def add_ring(body: mujoco.MjsBody, name: str, inner: tuple[float, float],
             z: tuple[float, float], wall: float, rgba: Sequence[float],
             staves: int = 16) -> None:
    """A vertical tube or cone of `staves` boxes in `body`: inner radius `inner[0]` at
    height `z[0]` to `inner[1]` at `z[1]`, `wall` thick (the staves' inner faces touch
    the inner circle; their outer corners overlap where the cone narrows)."""
    dr, dz = inner[1] - inner[0], z[1] - z[0]
    slant = math.hypot(dr, dz)
    along = np.array([dr / slant, dz / slant])  # (radial, vertical) along the stave
    normal = np.array([along[1], -along[0]])  # outward, normal to the stave
    mid_r, mid_z = (inner[0] + inner[1]) / 2, (z[0] + z[1]) / 2
    half_w = (max(inner) + wall) * math.tan(math.pi / staves)
    for k in range(staves):
        phi = 2 * math.pi * k / staves
        e = np.array([math.cos(phi), math.sin(phi), 0.0])
        out = normal[0] * e + normal[1] * np.array([0.0, 0.0, 1.0])
        up = along[0] * e + along[1] * np.array([0.0, 0.0, 1.0])
        centre = mid_r * e + np.array([0.0, 0.0, mid_z]) + out * wall / 2
        add_geom(body, f"{name}{k}", "box", [wall / 2, half_w, slant / 2], rgba,
                 pos=centre.tolist(), quat=_stave_quat(out, up))


PIPETTE_TIP_RADIUS = 0.003


def add_pipette(spec: mujoco.MjSpec, name: str, mass: float = 0.015) -> ObjectInfo:
    """A glass dropper pipette lying along x: a 10 cm barrel (12 mm across), a 4.5 cm
    drawn tip (6 mm) at +x and a rubber bulb (16 mm) at -x; 15 g.

    Round parts resist rolling like `add_capsule` (condim 6, `ROLLING_FRICTION`).
    Points `tip` (+x end, the one that goes in), `bulb_end` (-x end), `centre`; axis
    `long` points from the bulb to the tip.
    """
    body = free_body(spec, name)
    roll = [*DEFAULT_FRICTION[:2], ROLLING_FRICTION]
    barrel, tip, bulb = 0.05, 0.0225, 0.015  # half lengths
    r_barrel, r_tip, r_bulb = 0.006, PIPETTE_TIP_RADIUS, 0.008
    add_geom(body, f"{name}/barrel", "capsule", [r_barrel, barrel - r_barrel], GLASS,
             0.5 * mass, roll, condim=6, quat=ALONG_X)
    add_geom(body, f"{name}/tip", "capsule", [r_tip, tip], GLASS, 0.1 * mass, roll,
             condim=6, quat=ALONG_X, pos=[barrel + tip - r_tip, 0.0, 0.0])
    add_geom(body, f"{name}/bulb", "capsule", [r_bulb, bulb - r_bulb], RUBBER, 0.4 * mass,
             roll, condim=6, quat=ALONG_X, pos=[-barrel - bulb + r_bulb, 0.0, 0.0])
    front, back = barrel + 2 * tip - r_tip, -barrel - 2 * bulb + r_bulb
    return ObjectInfo(name, name, f"{name}/free", False, r_bulb, max(front, -back),
                      points={"tip": (name, (front, 0.0, 0.0)),
                              "bulb_end": (name, (back, 0.0, 0.0)),
                              "centre": (name, (0.0, 0.0, 0.0))},
                      axes={"long": (name, (1.0, 0.0, 0.0))})

# The flask's neck: 15 mm inner radius, and a wall thick enough (4.5 mm, with the
# pipette's 3 mm tip radius: 22.5 mm from the axis) that a tip held outside the neck
# can never be within InsertPipette's 0.02 m of the opening's centre.
NECK_RADIUS, NECK_WALL = 0.015, 0.0045


def add_flask(spec: mujoco.MjSpec, name: str, base_radius: float = 0.045,
              shoulder: float = 0.09, height: float = 0.14) -> ObjectInfo:
    """A fixed (mocap: clamped to the bench) Erlenmeyer flask, 0.14 m tall: a conical
    glass body from a 4.5 cm base radius to the neck at `shoulder`, then a straight
    neck (`NECK_RADIUS`) up to the rim, hollow all through.

    Points: `entrance` (centre of the rim opening), `target` (3.5 cm down the neck, where
    an inserted tip ends); axis `bore` points up out of the neck.
    """
    body = mocap_body(spec, name)
    wall, floor = 0.003, 0.004
    add_geom(body, f"{name}/floor", "cylinder", [base_radius + wall, floor / 2], GLASS,
             pos=[0, 0, floor / 2])
    add_ring(body, f"{name}/cone", (base_radius, NECK_RADIUS), (floor, shoulder), wall,
             GLASS, staves=20)
    add_ring(body, f"{name}/neck", (NECK_RADIUS, NECK_RADIUS), (shoulder, height),
             NECK_WALL, GLASS)
    return ObjectInfo(name, name, None, True, 0.0, base_radius + wall,
                      points={"entrance": (name, (0.0, 0.0, height)),
                              "target": (name, (0.0, 0.0, height - 0.035))},
                      axes={"bore": (name, UP)})


def add_corral(spec: mujoco.MjSpec, name: str, at: Vec3, half: float = 0.17,
               height: float = 0.04, wall: float = 0.01) -> ObjectInfo:
    """A fixed square fence (inner half width `half`, `height` tall) standing where it is
    built, at `at` (world: the middle of the table's top there), keeping the clutter
    together."""
    body = mocap_body(spec, name)
    body.pos = list(at)
    side = half + wall
    for k, (x, y) in enumerate(((1, 0), (-1, 0), (0, 1), (0, -1))):
        size = [wall / 2, side, height / 2] if x else [side, wall / 2, height / 2]
        add_geom(body, f"{name}/wall{k}", "box", size, WOOD,
                 pos=[x * (half + wall / 2), y * (half + wall / 2), height / 2])
    return ObjectInfo(name, name, None, True, 0.0, side * math.sqrt(2))


def add_clutter(spec: mujoco.MjSpec, names: Sequence[str], mass: float = 0.05,
                ) -> dict[str, ObjectInfo]:
    """Distractors, cycling through primitive shapes smaller than the 5 cm target (a 3.4 cm
    box, a 3.6 cm ball, a 3.4 cm wide and tall cylinder) and the non-green
    `DISTRACTOR_COLOURS`."""
    out = {}
    for k, name in enumerate(names):
        rgba = DISTRACTOR_COLOURS[k % len(DISTRACTOR_COLOURS)]
        shape = k % 3
        if shape == 0:
            out[name] = add_free_box(spec, name, (0.017, 0.017, 0.017), mass, rgba)
        elif shape == 1:
            out[name] = add_sphere(spec, name, 0.018, mass, rgba)
        else:
            out[name] = add_cylinder(spec, name, 0.017, 0.017, mass, rgba)
    return out


def add_green_cube(spec: mujoco.MjSpec, name: str, half: float = 0.025,
                   mass: float = 0.1) -> ObjectInfo:
    """The target: a green 5 cm cube (like PickCube's)."""
    return add_free_box(spec, name, (half, half, half), mass, GREEN)


# The container: a slot 10 cm long and 2.4 cm wide inside, 11 cm walls (the paper's).
SLOT_HALF = (0.05, 0.012)
CONTAINER_HEIGHT, CONTAINER_FLOOR = 0.11, 0.01


def add_slot_container(spec: mujoco.MjSpec, name: str, wall: float = 0.006) -> ObjectInfo:
    """A fixed (mocap: fixed to the table) small container: an open box `SLOT_HALF`
    inside, `CONTAINER_HEIGHT` tall, its long side along x. Point `slot` is the middle
    of its floor's top."""
    body = mocap_body(spec, name)
    colour = (0.35, 0.4, 0.5, 1.0)
    hx, hy = SLOT_HALF[0] + wall, SLOT_HALF[1] + wall
    add_geom(body, f"{name}/floor", "box", [hx, hy, CONTAINER_FLOOR / 2], colour,
             pos=[0, 0, CONTAINER_FLOOR / 2])
    zc, hz = CONTAINER_HEIGHT / 2, CONTAINER_HEIGHT / 2
    for k, sign in enumerate((1, -1)):
        add_geom(body, f"{name}/long{k}", "box", [hx, wall / 2, hz], colour,
                 pos=[0, sign * (SLOT_HALF[1] + wall / 2), zc])
        add_geom(body, f"{name}/end{k}", "box", [wall / 2, SLOT_HALF[1], hz], colour,
                 pos=[sign * (SLOT_HALF[0] + wall / 2), 0, zc])
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(hx, hy),
                      points={"slot": (name, (0.0, 0.0, CONTAINER_FLOOR))})


def add_thin_plate(spec: mujoco.MjSpec, name: str, size: Vec3 = (0.08, 0.006, 0.13),
                   mass: float = 0.05) -> ObjectInfo:
    """A thin rigid plate (a card, a ruler: `size` wide, thick, tall) standing on its
    long edge, its face across y; its origin at the middle of its bottom edge, so it
    stands on its support at `rest_height` 0. Points `centre`, `top` (middle of its top
    edge); axis `long` is along its width (body x)."""
    body = free_body(spec, name)
    w, t, h = size
    add_geom(body, f"{name}/geom", "box", [w / 2, t / 2, h / 2], (0.95, 0.95, 0.9, 1.0),
             mass, pos=[0, 0, h / 2])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, w / 2,
                      points={"centre": (name, (0.0, 0.0, h / 2)),
                              "top": (name, (0.0, 0.0, h))},
                      axes={"long": (name, (1.0, 0.0, 0.0)), "up": (name, UP)})

