"""Kitchen appliances for the long-horizon tasks: a tabletop fridge, a microwave and a
countertop oven with timer dials, and a trash bin whose lid a turn-button latch holds
shut. All fixed (mocap roots), facing +x like `hinged` (tasks turn them yaw pi).

Containment is a box in one body's frame, given as two points `<space>_lo` and
`<space>_hi` (its corners) so tasks read it from the `ObjectInfo`, not from here.
"""

from __future__ import annotations

import dataclasses
import math

import mujoco

from dexbench.assets.articulated import ACCENT, DARK, GREY
from dexbench.assets.hinged import _carcass, _door, add_microwave
from dexbench.assets.objects import ObjectInfo, add_geom, mocap_body
from dexbench.assets.parts import add_joint

WHITE = (0.92, 0.92, 0.9, 1.0)
BIN = (0.25, 0.45, 0.3, 1.0)
WALL = 0.01  # m: `hinged._carcass` wall thickness the appliances are built with
PANEL = 0.12  # m: `hinged.add_microwave`'s control strip width


def add_dial(base: mujoco.MjsBody, name: str, pos: tuple[float, float, float],
             turn: float = math.radians(270.0)) -> tuple[str, tuple[float, float], tuple]:
    """A timer dial on an appliance's top (vertical axis, 0 = off, up to `turn`): a hub
    with a pointer bar (point `tip` its end) fingers push round, as `turned.add_knob`.

    Moulded plastic, 30 g; damping 0.01 N m s/rad and friction loss 0.02 N m: it stays at
    the setting it is left at. Mounted on top (not on the front panel, as on many
    toaster ovens) so that a hand reaches it from above. Returns (joint, range, tip)."""
    knob = base.add_body(name=f"{name}/knob", pos=list(pos))
    joint = add_joint(knob, f"{name}", "hinge", (0, 0, 1), (0.0, turn), 0.01, 0.02)
    add_geom(knob, f"{name}/hub", "cylinder", [0.022, 0.008], DARK, 0.015, pos=[0, 0, 0.008])
    add_geom(knob, f"{name}/bar", "box", [0.035, 0.006, 0.012], ACCENT, 0.015,
             pos=[-0.015, 0, 0.028])
    return joint, (0.0, turn), (f"{name}/knob", (-0.045, 0.0, 0.028))


def _with(info: ObjectInfo, joints: dict, points: dict) -> ObjectInfo:
    return dataclasses.replace(info, joints={**info.joints, **joints},
                               points={**info.points, **points})


def add_dial_appliance(spec: mujoco.MjSpec, name: str, size: tuple[float, float, float],
                       dials: int) -> ObjectInfo:
    """`hinged.add_microwave` (the cavity behind a side-hinged door) with `dials` timer
    dials on top of its control strip: joints `<name>/dial<k>`, points `dial<k>`, and the
    cavity's corners `cavity_lo` / `cavity_hi` (base frame, floor to ceiling) and floor
    centre `cavity`. A microwave (two dials), or a countertop oven (one)."""
    hx, hy, hz = size
    info = add_microwave(spec, name, size)
    base = spec.body(name)
    joints, points = {}, {}
    for k in range(dials):
        x = 0.0 if dials == 1 else hx * (0.5 - k)
        joint, limits, tip = add_dial(base, f"{name}/dial{k}", (x, hy - PANEL / 2, 2 * hz))
        joints[joint], points[f"dial{k}"] = limits, tip
    lo = (-hx + 2 * WALL, -hy + 2 * WALL, 2 * WALL)
    hi = (hx, hy - PANEL, 2 * hz - 2 * WALL)
    points |= {"cavity_lo": (name, lo), "cavity_hi": (name, hi),
               "cavity": (name, ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]))}
    return _with(info, joints, points)


def add_fridge(spec: mujoco.MjSpec, name: str, size: tuple[float, float, float] = (
        0.15, 0.17, 0.16), opening: float = math.radians(110.0)) -> ObjectInfo:
    """A tabletop mini fridge (0.30 x 0.34 x 0.32 m), one compartment behind a door on a
    vertical hinge at its -y edge, opening to `opening`.

    The insulated door (foam between steel skins) weighs 1.8 kg; its magnetic seal is not
    modelled (no latch), hinge damping 0.3 N m s/rad and friction loss 0.2 N m hold it
    where it is left. Points: `handle`, `shelf` (the floor's centre), `inside_lo` /
    `inside_hi` (the compartment's corners, base frame).
    """
    hx, hy, hz = size
    base = mocap_body(spec, name)
    _carcass(base, name, hx, hy, hz, WALL, WHITE)
    joint, handle = _door(base, name, "door", (hx, -hy), 2 * hy, (0.005, 2 * hz), 0.03, 1.8,
                          opening, 0.3, 0.2, WHITE, hz * 1.3)
    lo, hi = (-hx + 2 * WALL, -hy + 2 * WALL, 2 * WALL), (hx, hy - 2 * WALL, 2 * hz - 2 * WALL)
    return ObjectInfo(name, name, None, True, 0.0, float(math.hypot(hx, hy)),
                      joints={joint: (0.0, opening)},
                      points={"handle": (f"{name}/door", handle),
                              "shelf": (name, (0.0, 0.0, 2 * WALL)),
                              "inside_lo": (name, lo), "inside_hi": (name, hi)})


def add_trash_bin(spec: mujoco.MjSpec, name: str, half: tuple[float, float, float] = (
        0.10, 0.12, 0.11), open_angle: float = math.radians(100.0)) -> ObjectInfo:
    """A countertop trash bin (0.20 x 0.24 x 0.22 m, 4 mm plastic walls) with a lid
    hinged along its +x top edge (front, with a lifting tab, at -x as `lidded`'s boxes)
    and a turn-button latch on the front wall's top.

    The lid (0.25 kg) opens with positive angles from 0 (shut on the rim) to
    `open_angle`, leaning back on its stop; no spring, so past upright it falls shut. The
    latch is a 45 mm bar on a post at the front (joint `<name>/latch`, 0 to 90 deg): at 0
    it lies along the front edge, turned 90 deg it reaches 33 mm over the shut lid, 1.5 mm
    above it, so the lid cannot lift: latched. The bar collides with the lid (sibling
    bodies), so a bar turned while the lid is open stops the lid shutting. Points: `tab`,
    `latch_tip`, `inside_lo` / `inside_hi` (the bin's inside, base frame).
    """
    hx, hy, hz = half
    t, gap, lt = 0.004, 0.001, 0.005
    base = mocap_body(spec, name)
    for part, size, pos in (("floor", (hx, hy, t), (0, 0, t)),
                            ("front", (t, hy, hz), (-hx + t, 0, hz)),
                            ("back", (t, hy, hz), (hx - t, 0, hz)),
                            ("left", (hx, t, hz), (0, hy - t, hz)),
                            ("right", (hx, t, hz), (0, -hy + t, hz))):
        add_geom(base, f"{name}/{part}", "box", size, BIN, pos=pos)
    lid = base.add_body(name=f"{name}/lid", pos=[hx, 0, 2 * hz + gap])
    hinge = add_joint(lid, f"{name}/hinge", "hinge", (0, 1, 0), (0.0, open_angle), 0.03, 0.02)
    add_geom(lid, f"{name}/lid", "box", [hx + 0.003, hy + 0.003, lt], BIN, 0.23,
             pos=[-hx, 0, lt])
    tab = 0.025
    add_geom(lid, f"{name}/tab", "box", [tab / 2, 0.03, 0.004], DARK, 0.02,
             pos=[-2 * hx - 0.003 - tab / 2, 0, 0.004])
    pivot = (-hx - 0.012, 0.075, 2 * hz + gap + 2 * lt + 0.0015 + 0.005)
    add_geom(base, f"{name}/post", "box", [0.005, 0.005, 0.03], GREY,
             pos=[pivot[0], pivot[1], pivot[2] - 0.03])
    bar = base.add_body(name=f"{name}/latch", pos=list(pivot))
    latch = add_joint(bar, f"{name}/latch", "hinge", (0, 0, -1), (0.0, math.pi / 2), 0.01,
                      0.02)
    add_geom(bar, f"{name}/bar", "box", [0.006, 0.0225, 0.005], ACCENT, 0.01,
             pos=[0, 0.0225, 0])
    return ObjectInfo(name, name, None, True, 0.0, float(math.hypot(hx + tab, hy)),
                      joints={hinge: (0.0, open_angle), latch: (0.0, math.pi / 2)},
                      points={"tab": (f"{name}/lid", (-2 * hx - tab + 0.005, 0.0, 0.0)),
                              "latch_tip": (f"{name}/latch", (0.0, 0.04, 0.0)),
                              "inside_lo": (name, (-hx + 2 * t, -hy + 2 * t, 2 * t)),
                              "inside_hi": (name, (hx - 2 * t, hy - 2 * t, 2 * hz))})
