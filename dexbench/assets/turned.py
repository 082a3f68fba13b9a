"""Turned parts: a rotary knob on a fixed base and a bucket's bail handle.

The knob turns about the vertical axis within +-90 deg (180 deg in all), 0 in the
middle; a bar across its top gives fingers something to push. The bucket is free; its
bail hangs on a hinge through two lugs at the rim, upright at 0 and stopped by the lugs
at +-`rest` on either side, where it lies nearly flat over the rim. Joints carry light
damping and friction loss (`parts.add_joint`) so they stay where they are left.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.articulated import ACCENT, DARK, GREY
from dexbench.assets.meshes import add_lathe_object
from dexbench.assets.objects import ObjectInfo, add_geom, mocap_body
from dexbench.assets.parts import add_joint

PAIL = (0.2, 0.45, 0.75, 1.0)
WIRE = (0.6, 0.6, 0.62, 1.0)


def add_knob(spec: mujoco.MjSpec, name: str, turn: float = math.pi) -> ObjectInfo:
    """A rotary selector knob (a stove or gas-valve dial) on a 6 cm pedestal, turning
    `turn` in all about +z, from -turn/2 to +turn/2; a pointer bar 12 cm long across its
    top (point `tip`: its end at -x, where fingers push it round).

    The knob and bar are moulded plastic, 40 g; damping 0.01 N m s/rad and friction loss
    0.02 N m: a dial turns easily but stays at the setting it is left at.
    """
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/pedestal", "box", [0.04, 0.04, 0.03], GREY, pos=[0, 0, 0.03])
    knob = base.add_body(name=f"{name}/knob", pos=[0, 0, 0.06])
    joint = add_joint(knob, f"{name}/dial", "hinge", (0, 0, 1), (-turn / 2, turn / 2), 0.01,
                      0.02)
    add_geom(knob, f"{name}/hub", "cylinder", [0.025, 0.01], DARK, 0.02, pos=[0, 0, 0.01])
    add_geom(knob, f"{name}/bar", "box", [0.06, 0.008, 0.014], ACCENT, 0.02,
             pos=[-0.02, 0, 0.034])
    return ObjectInfo(name, name, None, True, 0.0, 0.085, joints={joint: (-turn / 2, turn / 2)},
                      points={"tip": (f"{name}/knob", (-0.075, 0.0, 0.034))})


def add_bucket(spec: mujoco.MjSpec, name: str, radius: float = 0.09, height: float = 0.13,
               mass: float = 0.35, rest: float = math.radians(85.0)) -> ObjectInfo:
    """A 3-litre plastic pail (18 cm across the rim, 13 cm tall, 0.35 kg of HDPE) with a
    steel-wire bail (4 mm wire, a plastic grip tube in its middle, 70 g) on a hinge about
    y through two lugs just outside the rim. The lugs stop the bail at +-`rest`.

    Hinge damping 0.005 N m s/rad and friction loss 0.005 N m: a wire in a moulded lug
    swings freely, so the bail falls back onto its stop when let go early. Point `grip`
    is the grip tube's underside when the bail lies on its -x stop (its local -x).
    """
    wall = 0.003
    body = add_lathe_object(spec, name, [(radius - 0.015, 0.0), (radius, height)], wall, mass,
                            PAIL, bottom_thickness=0.004)
    span = radius + 0.012  # the lugs stand 12 mm outside the rim
    for sy in (1, -1):
        add_geom(body, f"{name}/lug{sy}", "box", [0.008, 0.006, 0.012], PAIL, 0.005,
                 pos=[0, sy * (radius + 0.004), height - 0.012])
    bail = body.add_body(name=f"{name}/bail", pos=[0, 0, height - 0.008])
    joint = add_joint(bail, f"{name}/handle", "hinge", (0, 1, 0), (-rest, rest), 0.005, 0.005)
    # The bail: a semicircle of radius `span` in the hinge frame's yz plane, as 8 capsules.
    arc = [(span * math.cos(math.pi * k / 8), span * math.sin(math.pi * k / 8))
           for k in range(9)]
    for k in range(8):
        (y0, z0), (y1, z1) = arc[k], arc[k + 1]
        add_geom(bail, f"{name}/wire{k}", "capsule", [0.002], WIRE, 0.005,
                 fromto=[0, y0, z0, 0, y1, z1])
    add_geom(bail, f"{name}/grip", "capsule", [0.011], DARK, 0.03,
             fromto=[0, -0.035, span, 0, 0.035, span])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, span + 0.01,
                      joints={joint: (-rest, rest)},
                      points={"grip": (f"{name}/bail", (-0.011, 0.0, span))})
