"""Fastened parts for the contact-rich tasks: a nut on a threaded bolt, a gear on its
shaft, a charger plug and its socket.

Every bore is built from convex pieces (staves round the hole), so a part goes on only
where it physically fits: the clearances are the tasks' tolerances or less.

The thread (MuJoCo has no screw joint): the bolt carries a hidden follower, a short hex
key with a flange under it, on a slide and a hinge along the bolt's axis whose values
are tied by a joint equality (descent = pitch x turns) for the whole episode, so the
follower can only go down by turning. The nut's bore is a hex hole that fits over the
key only when their flats line up (within about 12 deg): the nut drops onto the flange,
and from then on turning the nut turns the key through contact, and the key's descent
lets the nut down with it. The follower stands for the engaged thread flanks between nut
and bolt, so its geoms collide with the nut alone (contact bits `THREAD`): a finger
cannot turn it, nor does anything but the nut rest on it. Friction loss on the hinge
makes the coarse thread self-locking under the nut's weight and a light press.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from dexbench.assets.objects import (
    ALONG_X,
    ObjectInfo,
    _frame_quat,
    add_geom,
    add_hole_block,
    free_body,
    mocap_body,
)
from dexbench.assets.parts import add_joint, add_visual

STEEL = (0.62, 0.64, 0.68, 1.0)
BRASS = (0.80, 0.62, 0.25, 1.0)
DARK = (0.18, 0.18, 0.2, 1.0)
THREAD = 2  # contact bit of the thread follower; the nut's geoms carry it too
NUT_BITS = 1 | THREAD
NUT_HEIGHT = 0.04  # m
PIN_DROP = 0.01  # m: the charger's pin below the middle of its face
# The pitch equality, stiff: MuJoCo softens a constraint by an estimate of its inverse
# inertia, so it is written as turn = descent x 2 pi / pitch (in the hinge's units; the
# other way round, the light key's 1/inertia against a 1.3 mm/rad coefficient lets a
# press slide it down millimetres without turning). Two timesteps' time constant,
# impedance 0.9999: a 10 N press gives way by a micrometre.
TIGHT_REF = [0.008, 1.0]
TIGHT_IMP = [0.999, 0.9999, 0.001, 0.5, 2.0]


def _ring(body: mujoco.MjsBody, name: str, inner: float, outer: float, half_height: float,
          sides: int, rgba, mass: float, z: float = 0.0, phase: float = 0.0,
          bits: int = 1) -> None:
    """A prismatic ring of `sides` boxes round the body's z axis: a regular polygon hole
    of inradius `inner` (flats normal to angle `phase` + k 2pi/sides) in a polygon of
    inradius `outer`."""
    half_w = outer * math.tan(math.pi / sides)
    for k in range(sides):
        phi = phase + 2 * math.pi * k / sides
        radial = np.array([math.cos(phi), math.sin(phi), 0.0])
        pos = radial * (inner + outer) / 2 + [0.0, 0.0, z]
        add_geom(body, f"{name}{k}", "box", [(outer - inner) / 2, half_w, half_height], rgba,
                 mass / sides, pos=pos.tolist(), quat=_frame_quat(radial, np.array([0, 0, 1.0])),
                 contype=bits, conaffinity=bits)


def add_nut(spec: mujoco.MjSpec, name: str, across_flats: float = 0.05, height: float = NUT_HEIGHT,
            bore: float = 0.011, mass: float = 0.06) -> ObjectInfo:
    """A large, long hex nut (5 cm across the flats, 4 cm tall: a coupling nut's
    proportions, big enough for a hand to grip; 60 g of plastic, a toy-construction nut)
    standing,
    its bore a hex hole of inradius `bore` with a flat
    normal to the body's +x (axis `key`). Origin at its centre; point `bottom` is the
    bore's centre on the bottom face (it goes onto the bolt first), `centre` the middle;
    axis `down` points out of the bottom face."""
    body = free_body(spec, name)
    _ring(body, f"{name}/side", bore, across_flats / 2, height / 2, 6, BRASS, mass,
          bits=NUT_BITS)
    return ObjectInfo(name, name, f"{name}/free", False, height / 2,
                      across_flats / 2 / math.cos(math.pi / 6),
                      points={"bottom": (name, (0.0, 0.0, -height / 2)),
                              "centre": (name, (0.0, 0.0, 0.0))},
                      axes={"down": (name, (0.0, 0.0, -1.0)), "key": (name, (1.0, 0.0, 0.0))})


def add_threaded_bolt(spec: mujoco.MjSpec, name: str, pitch: float = 0.008, turns: float = 1.5,
                      key_flats: float = 0.010, shaft_radius: float = 0.0095,
                      stand: float = 0.04,
                      friction: float = 0.02) -> ObjectInfo:
    """A bolt standing in a fixed block (`stand` tall), threaded `turns` turns of coarse
    `pitch` (8 mm, a toy-construction thread) down to a shoulder, with its thread
    follower (module docstring): key of inradius `key_flats` (1 mm inside the nut's hex
    bore), 12 mm tall, on a 6 mm thick flange of 16 mm radius, 20 g (a light
    follower makes MuJoCo's contacts on it soft: a pressed nut sank through), turning
    clockwise from above (negative
    about +z: a right-hand thread) to go down. Friction loss `friction` (N m) on the turn:
    with it the thread holds the nut's weight and a press of up to about 2 pi friction /
    pitch (15 N) without turning; harder, the coarse thread spins down under it.

    Points: `entrance` the bolt's tip, `start` the flange top where an engaged nut's
    bottom rests before turning (on the follower), `seated` where it rests threaded
    down the full `turns` (the shoulder). Axes: `bore` up the bolt, `key` the
    follower's flat normal (the nut's `key` lines up with it, modulo 60 deg)."""
    base = mocap_body(spec, name)
    drop = pitch * turns
    seated = stand + 0.03
    start = seated + drop
    key_height = 0.012
    tip = start + key_height + 0.012
    add_geom(base, f"{name}/block", "box", [0.03, 0.03, stand / 2], DARK, pos=[0, 0, stand / 2])
    add_geom(base, f"{name}/shaft", "cylinder", [shaft_radius, (tip - stand) / 2], STEEL,
             pos=[0, 0, (stand + tip) / 2])
    add_geom(base, f"{name}/shoulder", "cylinder", [0.022, 0.0015], STEEL,
             pos=[0, 0, seated - 0.0015])
    for k in range(int((tip - seated) / pitch)):
        add_visual(base, f"{name}/crest{k}", "cylinder", [shaft_radius + 0.0008, 0.0008],
                   STEEL, pos=[0, 0, seated + (k + 0.5) * pitch])
    follower = base.add_body(name=f"{name}/follower", pos=[0, 0, start])
    travel, turn = (-drop, 0.0), (-2 * math.pi * turns, 0.0)
    slide = add_joint(follower, f"{name}/advance", "slide", (0, 0, 1), travel, 0.0, 0.0,
                      armature=1e-4)
    hinge = add_joint(follower, f"{name}/thread", "hinge", (0, 0, 1), turn, 0.001, friction,
                      armature=1e-5)
    spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name=f"{name}/pitch", name1=hinge,
                      name2=slide, data=[0.0, 2 * math.pi / pitch] + [0.0] * 10,
                      solref=TIGHT_REF, solimp=TIGHT_IMP)
    hidden = {"contype": THREAD, "conaffinity": THREAD, "group": 3}
    add_geom(follower, f"{name}/flange", "cylinder", [0.016, 0.003], STEEL, 0.01,
             pos=[0, 0, -0.003], **hidden)
    half_w = key_flats * math.tan(math.pi / 6)
    for k in range(3):
        add_geom(follower, f"{name}/key{k}", "box", [key_flats, half_w, key_height / 2], STEEL,
                 0.01 / 3, pos=[0, 0, key_height / 2], euler=[0, 0, k * math.pi / 3],
                 **hidden)
    return ObjectInfo(
        name, name, None, True, 0.0, 0.045, joints={slide: travel, hinge: turn},
        points={"entrance": (name, (0.0, 0.0, tip)), "start": (f"{name}/follower", (0, 0, 0)),
                "seated": (name, (0.0, 0.0, seated))},
        axes={"bore": (name, (0.0, 0.0, 1.0)), "key": (f"{name}/follower", (1.0, 0.0, 0.0))})


def add_gear(spec: mujoco.MjSpec, name: str, radius: float = 0.025, thickness: float = 0.04,
             bore: float = 0.0075, teeth: int = 12, mass: float = 0.06) -> ObjectInfo:
    """A thick spur gear (5 cm root diameter, 12 teeth 5 mm tall, 4 cm thick: a hand
    grips it round the rim; 60 g of plastic) lying flat, with a round bore of inradius
    `bore` through it (16 staves).
    Origin at its centre; point `hub` the bore's centre on the bottom face (it goes onto
    the shaft first); axis `down` out of the bottom face."""
    body = free_body(spec, name)
    _ring(body, f"{name}/web", bore, radius, thickness / 2, 16, BRASS, 0.85 * mass)
    for k in range(teeth):
        phi = 2 * math.pi * k / teeth
        add_geom(body, f"{name}/tooth{k}", "box", [0.003, 0.0035, thickness / 2], BRASS,
                 0.15 * mass / teeth, pos=[(radius + 0.002) * math.cos(phi),
                                           (radius + 0.002) * math.sin(phi), 0.0],
                 euler=[0, 0, phi])
    return ObjectInfo(name, name, f"{name}/free", False, thickness / 2, radius + 0.005,
                      points={"hub": (name, (0.0, 0.0, -thickness / 2))},
                      axes={"down": (name, (0.0, 0.0, -1.0))})


def add_gear_base(spec: mujoco.MjSpec, name: str, shaft_radius: float = 0.0055,
                  height: float = 0.10, shaft_length: float = 0.015) -> ObjectInfo:
    """A fixed gear base: a foot plate, a 3 cm column `height` tall whose top is the
    gear's seat, and a steel shaft `shaft_length` above it (round-tipped: a capsule, the
    chamfer that guides a bore on). The column is narrow so the fingers holding a gear
    round its rim pass beside it. Points: `entrance` the shaft's tip, `seat` the column
    top (a seated gear's `hub`); axis `shaft` up. The shaft is half as long as the gear
    is thick: the bore bears on it only there, as on a stub axle."""
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/foot", "cylinder", [0.045, 0.004], DARK, pos=[0, 0, 0.004])
    add_geom(base, f"{name}/column", "cylinder", [0.015, height / 2], DARK,
             pos=[0, 0, height / 2])
    half = (shaft_length - shaft_radius) / 2
    add_geom(base, f"{name}/shaft", "capsule", [shaft_radius, half], STEEL,
             pos=[0, 0, height + half])
    return ObjectInfo(name, name, None, True, 0.0, 0.045,
                      points={"entrance": (name, (0.0, 0.0, height + shaft_length)),
                              "seat": (name, (0.0, 0.0, height))},
                      axes={"shaft": (name, (0.0, 0.0, 1.0))})


def add_charger_plug(spec: mujoco.MjSpec, name: str, pin_radius: float = 0.005,
                     pin_length: float = 0.025, size: tuple[float, float, float] = (0.1, 0.05,
                                                                                 0.05),
                     mass: float = 0.08) -> ObjectInfo:
    """A charger: a 10 x 5 x 5 cm brick (80 g, a plastic travel charger, square so a hand
    grips it like a block) lying flat, with a round barrel pin (`pin_radius` 5 mm, 2.5 cm
    long, its end rounded: the chamfer that guides it in) out of its +x face, `PIN_DROP`
    below its middle (the hand over the brick then clears the socket's top), a stub of
    cable out of the back. Point `tip` the pin's end, `grip` on its rear half (a hand
    holding it there stays clear of the socket when the pin is home); axis `pin` along
    the pin (body +x)."""
    body = free_body(spec, name)
    hx, hy, hz = (s / 2 for s in size)
    add_geom(body, f"{name}/brick", "box", [hx, hy, hz], DARK, 0.95 * mass)
    add_geom(body, f"{name}/pin", "capsule", [pin_radius, pin_length / 2 - pin_radius], STEEL,
             0.05 * mass, pos=[hx + pin_length / 2, 0, -PIN_DROP], quat=ALONG_X)
    add_visual(body, f"{name}/cable", "capsule", [0.004, 0.01], DARK, pos=[-hx - 0.01, 0, 0],
               quat=ALONG_X)
    return ObjectInfo(name, name, f"{name}/free", False, hz, hx + pin_length,
                      points={"tip": (name, (hx + pin_length, 0.0, -PIN_DROP)),
                              "grip": (name, (-0.4 * hx, 0.0, 0.0))},
                      axes={"pin": (name, (1.0, 0.0, 0.0))})


def add_socket(spec: mujoco.MjSpec, name: str, bore_radius: float = 0.007,
               depth: float = 0.025, axis_height: float = 0.06, mouth: float = 0.008,
               staves: int = 12) -> ObjectInfo:
    """A fixed charging socket: a block on a stand with a round receptacle (2 mm wider
    than the pin all round: the pin's tip cannot be off its axis by the task's 2.5 mm)
    `depth` deep, facing its -x side, and a 45 deg flared mouth `mouth` deep in front of
    it (a socket's chamfer, 12 slanted staves) that guides a pin in. A fully inserted
    2.5 cm pin (the brick against the mouth) is 1.7 cm past the opening. `entrance`,
    `target` and axis `bore` (out of the socket) as in `objects.add_hole_block`, whose
    geometry the rest is."""
    info = add_hole_block(spec, name, bore_radius=bore_radius, depth=depth,
                          axis_height=axis_height, wall=0.01, staves=staves)
    body = spec.body(name)
    out, e1 = np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    e2 = np.cross(out, e1)
    entrance = np.array(info.points["entrance"][1])
    thick = 0.004
    half_w = (bore_radius + mouth + thick) * math.tan(math.pi / staves)
    for k in range(staves):
        phi = 2 * math.pi * k / staves
        radial = math.cos(phi) * e1 + math.sin(phi) * e2
        slant = (out + radial) / math.sqrt(2.0)
        into = (radial - out) / math.sqrt(2.0)  # away from the axis, into the wall
        mid = entrance + (bore_radius + mouth / 2) * radial + (mouth / 2) * out
        add_geom(body, f"{name}/mouth{k}", "box", [thick / 2, half_w, mouth / math.sqrt(2.0)],
                 DARK, pos=(mid + thick / 2 * into).tolist(), quat=_frame_quat(into, slant))
    return info
