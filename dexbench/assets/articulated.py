"""Articulated objects: fixed mechanisms (mocap roots), a free laptop and a milk carton.

Joints are named `<name>/<joint>`, with realistic ranges, damping and friction loss so
they stay where a hand leaves them (the button is sprung instead). Objects face +x in
their own frame; tasks turn them towards the robot (yaw pi) at reset.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco

from dexbench.assets.objects import ObjectInfo, add_geom, free_body, mocap_body

GREY = (0.5, 0.5, 0.55, 1.0)
DARK = (0.2, 0.2, 0.22, 1.0)
ACCENT = (0.85, 0.35, 0.15, 1.0)
# Friction loss is a soft constraint: with MuJoCo's default impedance (0.9) a joint held
# only by friction creeps under a steady load (a laptop lid sags ~4 deg/s). Near-hard
# impedance makes it hold like dry friction.
HOLD = [0.999, 0.999, 0.001, 0.5, 2.0]


def _hinge(body: mujoco.MjsBody, name: str, axis: Sequence[float], lo: float, hi: float,
           damping: float, friction: float) -> str:
    body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(axis),
                   range=[lo, hi], damping=damping, frictionloss=friction, armature=1e-3,
                   solimp_friction=HOLD)
    return name


def add_switch(spec: mujoco.MjSpec, name: str, throw: float = 0.35) -> ObjectInfo:
    """A rocker switch on a base plate, rocking about y within +-`throw`.

    Off is the lower limit: there the +x end (point `press`) is raised, and pressing it
    down turns the switch on (towards the upper limit). The rocker is balanced, so it
    stays wherever it is left.
    """
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/plate", "box", [0.05, 0.04, 0.012], GREY, pos=[0, 0, 0.012])
    rocker = base.add_body(name=f"{name}/rocker", pos=[0, 0, 0.03])
    joint = _hinge(rocker, f"{name}/rocker", (0, 1, 0), -throw, throw, 0.02, 0.01)
    add_geom(rocker, f"{name}/paddle", "box", [0.035, 0.025, 0.006], ACCENT, 0.02)
    return ObjectInfo(name, name, None, True, 0.0, 0.065, joints={joint: (-throw, throw)},
                      points={"paddle": (f"{name}/rocker", (0.0, 0.0, 0.006)),
                              "press": (f"{name}/rocker", (0.03, 0.0, 0.006))})


def add_button(spec: mujoco.MjSpec, name: str, travel: float = 0.015,
               stiffness: float = 60.0, preload: float = 0.003) -> ObjectInfo:
    """A sprung push button; the joint is 0 when released and -`travel` fully pressed.

    The spring's rest point lies `preload` above the top stop, so the released cap is held
    against it (0.18 N by default) instead of floating; fully pressed takes about 1.1 N.
    """
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/housing", "box", [0.04, 0.04, 0.02], GREY, pos=[0, 0, 0.02])
    cap = base.add_body(name=f"{name}/cap", pos=[0, 0, 0.04], gravcomp=1.0)  # no sag
    cap.add_joint(name=f"{name}/press", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
                  range=[-travel, 0.0], stiffness=stiffness, springref=preload, damping=1.0,
                  armature=1e-3)
    add_geom(cap, f"{name}/cap", "cylinder", [0.022, 0.01], ACCENT, 0.02, pos=[0, 0, 0.01])
    return ObjectInfo(name, name, None, True, 0.0, 0.06,
                      joints={f"{name}/press": (-travel, 0.0)},
                      points={"cap": (f"{name}/cap", (0.0, 0.0, 0.02))})


def add_faucet(spec: mujoco.MjSpec, name: str, turn: float = math.radians(120)) -> ObjectInfo:
    """A faucet whose lever turns about the vertical axis from 0 (closed) to `turn`.

    Friction loss holds the lever wherever it is left; point `handle_tip` is its free end.
    """
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/column", "cylinder", [0.025, 0.08], GREY, pos=[0, 0, 0.08])
    add_geom(base, f"{name}/spout", "capsule", [0.012, 0.06], GREY, pos=[0.06, 0, 0.15],
             quat=[0.7071068, 0, 0.7071068, 0])
    lever = base.add_body(name=f"{name}/handle", pos=[0, 0, 0.17])
    joint = _hinge(lever, f"{name}/handle", (0, 0, 1), 0.0, turn, 0.05, 0.05)
    add_geom(lever, f"{name}/hub", "cylinder", [0.02, 0.012], DARK, 0.03)
    add_geom(lever, f"{name}/lever", "capsule", [0.01, 0.04], ACCENT, 0.03,
             pos=[-0.04, 0, 0.015], quat=[0.7071068, 0, 0.7071068, 0])
    return ObjectInfo(name, name, None, True, 0.0, 0.132, joints={joint: (0.0, turn)},
                      points={"handle_tip": (f"{name}/handle", (-0.08, 0.0, 0.015))})


def add_drawer_cabinet(spec: mujoco.MjSpec, name: str, travel: float = 0.25,
                       size: tuple[float, float, float] = (0.18, 0.20, 0.10)) -> ObjectInfo:
    """A cabinet (open front at +x) with one drawer sliding out along +x by `travel`.

    The joint is 0 when closed; damping and friction loss keep the drawer where a hand
    leaves it. Point `handle` is the middle of the handle bar.
    """
    hx, hy, hz = size
    t = 0.01
    base = mocap_body(spec, name)
    for part, half, pos in (("top", (hx, hy, t), (0, 0, 2 * hz - t)),
                            ("floor", (hx, hy, t), (0, 0, t)),
                            ("left", (hx, t, hz), (0, hy - t, hz)),
                            ("right", (hx, t, hz), (0, -hy + t, hz)),
                            ("back", (t, hy, hz), (-hx + t, 0, hz))):
        add_geom(base, f"{name}/{part}", "box", half, GREY, pos=pos)
    drawer = base.add_body(name=f"{name}/drawer", pos=[0, 0, hz])
    drawer.add_joint(name=f"{name}/drawer", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0],
                     range=[0.0, travel], damping=5.0, frictionloss=0.5, armature=0.01,
                     solimp_friction=HOLD)
    dx, dy, dz = hx - 2 * t, hy - 2.5 * t, hz - 2.5 * t
    for part, half, pos in (("bottom", (dx, dy, t / 2), (0, 0, -dz)),
                            ("front", (t, dy + t, dz), (hx - t, 0, 0)),
                            ("rear", (t / 2, dy, dz), (-dx, 0, 0)),
                            ("side0", (dx, t / 2, dz), (0, dy, 0)),
                            ("side1", (dx, t / 2, dz), (0, -dy, 0))):
        add_geom(drawer, f"{name}/drawer_{part}", "box", half, (0.7, 0.55, 0.4, 1), 0.15,
                 pos=pos)
    handle = (hx + 0.03, 0.0, 0.0)
    add_geom(drawer, f"{name}/handle", "capsule", [0.008, 0.05], DARK, 0.05, pos=handle,
             quat=[0.7071068, 0.7071068, 0, 0])
    for sy in (1, -1):
        add_geom(drawer, f"{name}/handle_post{sy}", "box", [0.012, 0.006, 0.006], DARK, 0.01,
                 pos=[hx + 0.012, sy * 0.04, 0])
    return ObjectInfo(name, name, None, True, 0.0, float(math.hypot(hx, hy)),
                      joints={f"{name}/drawer": (0.0, travel)},
                      points={"handle": (f"{name}/drawer", handle)})


def add_laptop(spec: mujoco.MjSpec, name: str, size: tuple[float, float] = (0.11, 0.16),
               mass: float = 1.2) -> ObjectInfo:
    """A free laptop; the hinge is on its +x edge and the lid opens with negative angles.

    At 0 the lid lies closed on the base; the range is (-110 deg, 0). The hinge's friction
    loss (0.5 N m) beats the lid's weight (at most ~0.4 N m), so, like a real laptop, the
    lid stays at any angle, and opening it needs the base held. Points: `lid_edge` (the
    free edge of the lid), `base_front` (the front edge of the base, opposite the hinge).
    """
    hx, hy = size
    base = free_body(spec, name)
    add_geom(base, f"{name}/base", "box", [hx, hy, 0.01], DARK, mass * 0.7, pos=[0, 0, 0.01])
    lid = base.add_body(name=f"{name}/lid", pos=[hx, 0, 0.026])
    lo = math.radians(-110.0)
    joint = _hinge(lid, f"{name}/hinge", (0, -1, 0), lo, 0.0, 0.3, 0.5)
    add_geom(lid, f"{name}/lid", "box", [hx, hy, 0.005], (0.3, 0.3, 0.35, 1), mass * 0.3,
             pos=[-hx, 0, 0])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, float(math.hypot(hx, hy)),
                      joints={joint: (lo, 0.0)},
                      points={"lid_edge": (f"{name}/lid", (-2 * hx, 0.0, 0.0)),
                              "base_front": (name, (-hx, 0.0, 0.02))})


def add_coffee_machine(spec: mujoco.MjSpec, name: str,
                       lever_turn: float = math.radians(90)) -> ObjectInfo:
    """A coffee machine facing +x: a cup spot under the spout and a lever on its +y side.

    The lever is horizontal (pointing +x) at 0 and is pushed down to `lever_turn`;
    friction loss holds it where it is left. Points: `cup_spot` (drip tray top, under the
    spout), `spout` (outlet), `lever_tip`.
    """
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/tower", "box", [0.08, 0.10, 0.17], DARK, pos=[-0.06, 0, 0.17])
    add_geom(base, f"{name}/head", "box", [0.07, 0.10, 0.04], DARK, pos=[0.08, 0, 0.30])
    add_geom(base, f"{name}/tray", "box", [0.07, 0.09, 0.006], GREY, pos=[0.08, 0, 0.006])
    add_geom(base, f"{name}/spout", "cylinder", [0.012, 0.015], GREY, pos=[0.09, 0, 0.245])
    lever = base.add_body(name=f"{name}/lever", pos=[-0.02, 0.105, 0.25])
    joint = _hinge(lever, f"{name}/lever", (0, 1, 0), 0.0, lever_turn, 0.05, 0.03)
    add_geom(lever, f"{name}/lever", "capsule", [0.008, 0.04], ACCENT, 0.03,
             pos=[0.04, 0.012, 0], quat=[0.7071068, 0, 0.7071068, 0])
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(0.15, 0.10),
                      joints={joint: (0.0, lever_turn)},
                      points={"cup_spot": (name, (0.09, 0.0, 0.012)),
                              "spout": (name, (0.09, 0.0, 0.23)),
                              "lever_tip": (f"{name}/lever", (0.08, 0.012, 0.0))})


def add_milk_carton(spec: mujoco.MjSpec, name: str, half: tuple[float, float, float] = (
        0.03, 0.03, 0.07), mass: float = 0.3) -> ObjectInfo:
    """A free milk carton with its spout at the top +x edge."""
    body = free_body(spec, name)
    add_geom(body, f"{name}/box", "box", half, (0.95, 0.95, 0.92, 1), mass, pos=[0, 0, half[2]])
    add_geom(body, f"{name}/spout", "box", [0.008, 0.012, 0.01], (0.2, 0.4, 0.8, 1), 0.005,
             pos=[half[0] - 0.008, 0, 2 * half[2] + 0.01])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, float(math.hypot(*half[:2])),
                      points={"spout": (name, (half[0], 0.0, 2 * half[2] + 0.02))},
                      axes={"up": (name, (0.0, 0.0, 1.0))})
