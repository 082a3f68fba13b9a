"""Desk objects: a flat folder and a stapler (free, hinged), a pen and a pen holder.

Like `articulated`, hinged parts face +x (their free edge) and their joints are named
`<name>/<joint>`, opening towards positive angles from 0 (closed), with friction loss
that holds them at any angle against their own weight.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.objects import (
    ALONG_X,
    DEFAULT_FRICTION,
    ROLLING_FRICTION,
    UP,
    ObjectInfo,
    add_geom,
    add_hole_block,
    free_body,
)
from dexbench.assets.parts import add_joint

OPENS_UP = (0.0, -1.0, 0.0)  # hinge axis along y: positive angles lift the +x side
PLASTIC = (0.15, 0.35, 0.75, 1.0)
METAL = (0.6, 0.62, 0.66, 1.0)
DARK = (0.15, 0.15, 0.17, 1.0)


def add_flat_folder(spec: mujoco.MjSpec, name: str, size: tuple[float, float] = (0.11, 0.155),
                    mass: float = 0.18) -> ObjectInfo:
    """An A4 folder (half extents `size`) whose flap is hinged on its -x edge.

    Joint `<name>/flap` runs from 0 (closed, lying on the base) to 170 deg. The flap
    overhangs the base's free (+x) edge by 1.2 cm, so a finger can lift it from below.
    Friction loss (0.1 N m) beats the flap's weight (at most 0.07 N m). Points:
    `flap_edge` (middle of the flap's free edge), `base_edge` (middle of the base's free
    edge), `hinge`. Axes: `up`, `hinge` (the joint axis, in the base frame).
    """
    hx, hy = size
    tb, tf, overhang = 0.0025, 0.002, 0.012
    base = free_body(spec, name)
    add_geom(base, f"{name}/base", "box", [hx, hy, tb], DARK, 0.65 * mass, pos=[0, 0, tb])
    flap = base.add_body(name=f"{name}/flap", pos=[-hx, 0, 2 * tb])
    hi = math.radians(170.0)
    joint = add_joint(flap, f"{name}/flap", "hinge", OPENS_UP, (0.0, hi), 0.01, 0.1)
    half_len = hx + overhang / 2
    add_geom(flap, f"{name}/flap", "box", [half_len, hy, tf], PLASTIC, 0.35 * mass,
             pos=[half_len, 0, tf])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0,
                      math.hypot(hx + overhang, hy),
                      joints={joint: (0.0, hi)},
                      points={"flap_edge": (f"{name}/flap", (2 * half_len, 0.0, tf)),
                              "base_edge": (name, (hx, 0.0, tb)),
                              "hinge": (name, (-hx, 0.0, 2 * tb))},
                      axes={"up": (name, UP), "hinge": (name, OPENS_UP)})


def add_stapler(spec: mujoco.MjSpec, name: str, mass: float = 0.33) -> ObjectInfo:
    """A desk stapler (0.17 m long) whose top arm is hinged at the back (-x) end.

    Joint `<name>/arm` runs from 0 (closed) to 90 deg. The arm overhangs the base's
    front by 1.2 cm (a lip to lift it by); friction loss (0.1 N m) holds it open against
    its weight (at most 0.08 N m). Points: `arm_lip` (underside of the arm's front end),
    `arm_top` (top of the arm over the staple), `base` (centre of the base plate, which
    sticks out 3 mm each side of the arm), `base_front`. Axes: `up`, `hinge`.
    """
    base = free_body(spec, name)
    bx, by, bz = 0.085, 0.022, 0.006
    add_geom(base, f"{name}/base", "box", [bx, by, bz], DARK, 0.6 * mass, pos=[0, 0, bz])
    add_geom(base, f"{name}/anvil", "box", [0.015, 0.01, 0.001], METAL, 0.02 * mass,
             pos=[0.06, 0, 2 * bz + 0.001])
    hinge_x = -bx + 0.012
    add_geom(base, f"{name}/block", "box", [0.012, 0.02, 0.01], DARK, 0.1 * mass,
             pos=[hinge_x, 0, 2 * bz + 0.01])
    arm = base.add_body(name=f"{name}/arm", pos=[hinge_x, 0, 2 * bz + 0.014])
    hi = math.radians(90.0)
    joint = add_joint(arm, f"{name}/arm", "hinge", OPENS_UP, (0.0, hi), 0.05, 0.1)
    half_len, az = 0.085, 0.01
    add_geom(arm, f"{name}/arm", "box", [half_len, 0.019, az], PLASTIC, 0.28 * mass,
             pos=[half_len, 0, 0])
    front = 2 * half_len
    return ObjectInfo(name, name, f"{name}/free", False, 0.0,
                      math.hypot(hinge_x + front, 0.019),
                      joints={joint: (0.0, hi)},
                      points={"arm_lip": (f"{name}/arm", (front - 0.005, 0.0, -az)),
                              "arm_top": (f"{name}/arm", (front - 0.03, 0.0, az)),
                              "base": (name, (0.0, 0.0, bz)),
                              "base_front": (name, (bx, 0.0, 2 * bz))},
                      axes={"up": (name, UP), "hinge": (name, OPENS_UP)})


def add_pen(spec: mujoco.MjSpec, name: str, length: float = 0.14, radius: float = 0.006,
            mass: float = 0.02) -> ObjectInfo:
    """A pen lying along x: a capsule barrel with a clip near its -x end.

    The barrel resists rolling like `add_capsule` (condim 6, `ROLLING_FRICTION`) and the
    clip stops it rolling over. Either end can go into a holder: points `tip` (+x end)
    and `tail` (-x end), `centre`. Axis `long` points from tail to tip.
    """
    body = free_body(spec, name)
    half = length / 2
    add_geom(body, f"{name}/barrel", "capsule", [radius, half - radius], PLASTIC, 0.9 * mass,
             [*DEFAULT_FRICTION[:2], ROLLING_FRICTION], condim=6, quat=ALONG_X)
    add_geom(body, f"{name}/clip", "box", [0.018, 0.0015, 0.0015], METAL, 0.1 * mass,
             pos=[-half + 0.03, 0, radius + 0.0015])
    return ObjectInfo(name, name, f"{name}/free", False, radius, half,
                      points={"tip": (name, (half, 0.0, 0.0)),
                              "tail": (name, (-half, 0.0, 0.0)),
                              "centre": (name, (0.0, 0.0, 0.0))},
                      axes={"long": (name, (1.0, 0.0, 0.0))})


def add_pen_holder(spec: mujoco.MjSpec, name: str, radius: float = 0.035,
                   depth: float = 0.10) -> ObjectInfo:
    """A fixed pen cup: a thin-walled (4 mm) vertical `add_hole_block`.

    Points `entrance` (centre of the opening, the rim) and `target` (5 mm above the
    floor); axis `bore` points up out of it.
    """
    return add_hole_block(spec, name, bore_radius=radius, depth=depth, vertical=True,
                          wall=0.004)
