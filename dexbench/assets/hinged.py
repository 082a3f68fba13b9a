"""Side-hinged doors: a cabinet and a microwave, fixed (mocap roots), facing +x.

Each door hangs on a vertical hinge at the front's -y edge and opens outwards (towards
+x, so towards a robot the task turns it to face) with positive joint angles, from 0
(closed) to its stop. Its handle is a horizontal bar on the outer face near the free
edge: a hand hanging its fingers behind the bar hooks it and pulls along the door's arc.
Hinges carry damping and friction loss (`parts.add_joint`) but no spring: a real cabinet
or microwave door stays where it is left. Point `handle` is the middle of the bar.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.articulated import DARK, GREY
from dexbench.assets.objects import ObjectInfo, add_geom, mocap_body
from dexbench.assets.parts import add_joint, add_visual

WOOD = (0.72, 0.58, 0.42, 1.0)
GLASS = (0.08, 0.1, 0.12, 1.0)
GAP = 0.002  # m between the closed door and the carcass front: no contact at rest
BAR_OUT = 0.035  # m the bar stands off the door face (bar pulls: 30-40 mm): room for fingers


def _carcass(body: mujoco.MjsBody, name: str, hx: float, hy: float, hz: float,
             t: float, rgba: tuple[float, ...]) -> None:
    """An open-fronted (+x) box of wall thickness `t` standing on z = 0."""
    for part, half, pos in (("top", (hx, hy, t), (0, 0, 2 * hz - t)),
                            ("floor", (hx, hy, t), (0, 0, t)),
                            ("left", (hx, t, hz), (0, hy - t, hz)),
                            ("right", (hx, t, hz), (0, -hy + t, hz)),
                            ("back", (t, hy, hz), (-hx + t, 0, hz))):
        add_geom(body, f"{name}/{part}", "box", half, rgba, pos=pos)


def _door(base: mujoco.MjsBody, name: str, joint: str, hinge: tuple[float, float],
          width: float, z: tuple[float, float], thick: float, mass: float,
          opening: float, damping: float, friction: float, rgba: tuple[float, ...],
          handle_z: float, side: float = 1.0) -> tuple[str, tuple[float, float, float]]:
    """A door panel from the hinge line at `hinge` (x, y) along +y by `width` (along -y
    for `side` -1: the mirror image, for a double door's other leaf), between heights
    `z`, opening (free edge towards +x) by up to `opening`; returns the joint and the
    handle's middle in the door frame."""
    door = base.add_body(name=f"{name}/door", pos=[hinge[0] + GAP, hinge[1], 0.0])
    add_joint(door, f"{name}/{joint}", "hinge", (0, 0, -side), (0.0, opening), damping,
              friction, armature=0.01)
    add_geom(door, f"{name}/door", "box", [thick / 2, width / 2, (z[1] - z[0]) / 2], rgba,
             mass, pos=[thick / 2, side * width / 2, (z[0] + z[1]) / 2])
    handle = (thick + BAR_OUT, side * (width - 0.07), handle_z)
    add_geom(door, f"{name}/handle", "capsule", [0.008, 0.05], DARK, 0.05, pos=handle,
             quat=[0.7071068, 0.7071068, 0, 0])
    for sy in (1, -1):
        add_geom(door, f"{name}/handle_post{sy}", "box", [BAR_OUT / 2, 0.006, 0.006], DARK,
                 0.01, pos=[thick + BAR_OUT / 2, handle[1] + sy * 0.04, handle_z])
    return f"{name}/{joint}", handle


def add_door_cabinet(spec: mujoco.MjSpec, name: str, joint: str = "door",
                     size: tuple[float, float, float] = (0.16, 0.18, 0.18),
                     opening: float = math.radians(100.0)) -> ObjectInfo:
    """A tabletop cupboard (0.32 x 0.36 x 0.36 m) with one overlay door on a vertical
    hinge, opening up to `opening` (concealed cabinet hinges stop at 95-110 deg).

    The 16 mm particle-board door (650 kg/m^3) weighs 1.3 kg; hinge damping 0.2 N m s/rad and
    friction loss 0.15 N m: it swings freely but does not coast on after a push.
    """
    hx, hy, hz = size
    base = mocap_body(spec, name)
    _carcass(base, name, hx, hy, hz, 0.01, WOOD)
    add_geom(base, f"{name}/shelf", "box", [hx - 0.02, hy - 0.02, 0.008], WOOD,
             pos=[0, 0, hz])
    joint_name, handle = _door(base, name, joint, (hx, -hy), 2 * hy, (0.005, 2 * hz),
                               0.016, 1.3, opening, 0.2, 0.15, WOOD, hz * 1.2)
    return ObjectInfo(name, name, None, True, 0.0, float(math.hypot(hx, hy)),
                      joints={joint_name: (0.0, opening)},
                      points={"handle": (f"{name}/door", handle)})


def add_microwave(spec: mujoco.MjSpec, name: str,
                  size: tuple[float, float, float] = (0.17, 0.24, 0.14),
                  opening: float = math.radians(95.0)) -> ObjectInfo:
    """A countertop microwave (0.34 x 0.48 x 0.28 m): the oven cavity behind a door on
    the -y side, the control panel on the +y side, the door hinged at its -y edge
    (a microwave's is on the left as one faces it) and stopping at `opening`.

    The door (metal frame, glass window) weighs 1.5 kg; no latch or spring is modelled,
    hinge damping 0.3 N m s/rad and friction loss 0.2 N m.
    """
    hx, hy, hz = size
    panel = 0.12  # m: width of the control panel strip
    base = mocap_body(spec, name)
    _carcass(base, name, hx, hy, hz, 0.01, GREY)
    add_geom(base, f"{name}/panel", "box", [hx, panel / 2, hz - 0.01], GREY,
             pos=[0, hy - panel / 2, hz])
    add_visual(base, f"{name}/keys", "box", [0.002, panel / 2 - 0.02, hz * 0.6], DARK,
               pos=[hx + 0.002, hy - panel / 2, hz])
    width = 2 * hy - panel
    joint_name, handle = _door(base, name, "door", (hx, -hy), width, (0.005, 2 * hz),
                               0.025, 1.5, opening, 0.3, 0.2, GREY, hz)
    add_visual(spec.body(f"{name}/door"), f"{name}/window", "box",
               [0.002, width / 2 - 0.06, hz - 0.05], GLASS, pos=[0.026, width / 2 - 0.02, hz])
    return ObjectInfo(name, name, None, True, 0.0, float(math.hypot(hx, hy)),
                      joints={joint_name: (0.0, opening)},
                      points={"handle": (f"{name}/door", handle)})
