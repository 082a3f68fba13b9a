"""Doors that face +x (fixed, mocap roots): a latched door in a frame and a double-door
cupboard.

`add_latched_door` is a door in a free-standing frame, kept shut by a real latch: its
lever handle turns a spindle through the door, and a cam (latch bolt) on the spindle's
back end lies behind the frame's strike post while the lever rests, so pulling the door
presses the cam into the post. Lifting the lever swings the cam out from behind the
post; a preloaded return spring brings the lever back when let go. `add_double_door_cabinet`
is the cupboard of `hinged` with two doors meeting in the middle, each with a bar handle
near the meeting edge.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.articulated import DARK
from dexbench.assets.hinged import GAP, WOOD, _carcass, _door
from dexbench.assets.objects import ObjectInfo, add_geom, mocap_body
from dexbench.assets.parts import add_joint, add_visual

POST = 0.03  # m: frame post width and depth (x)
LEVER_OUT = 0.035  # m the lever grip stands off the door face: room for the fingers
LEVER_LENGTH = 0.11  # m from the spindle to the lever's end (residential levers: 10-13 cm)
GRIP = 0.065  # m from the spindle to the middle of the lever's grip
SPINDLE_IN = 0.07  # m from the strike post's inner edge to the spindle
CAM_OVER = 0.014  # m the resting cam reaches in behind the post
CAM_HALF = (0.004, 0.005)  # m: the cam's half thickness (x) and half height (z)
LEVER_TRAVEL = math.radians(60.0)  # lever stop; the cam clears the post from ~38 deg
LEVER_SPRING = 0.3  # N m/rad return spring, preloaded `LEVER_PRELOAD` rad at rest
LEVER_PRELOAD = 0.2


def add_latched_door(spec: mujoco.MjSpec, name: str, opening_half: float = 0.15,
                     height: float = 0.40, swing: float = math.radians(100.0)) -> ObjectInfo:
    """A 0.34 x 0.38 m door on a vertical hinge at its -y edge, in a frame whose opening
    is 2 `opening_half` wide; it swings out (+x) up to `swing`. Joints `<name>/door` and
    `<name>/lever`; points `handle` (the lever's grip) and `latch` (the cam's tip).

    The 20 mm door (pine, 500 kg/m^3) weighs 1.3 kg, hinge damping 0.3 N m s/rad and
    friction loss 0.2 N m. The lever (0.1 kg) lifts by up to 60 deg against a 0.3 N m/rad
    return spring preloaded to 0.06 N m (lever-latch springs hold 0.05-0.5 N m): at its
    stop it takes about 6 N at the grip. Its cam, a 10 mm steel bar, reaches 14 mm
    behind the strike post's back face with 2 mm play, so a door pulled with the lever
    at rest opens by that play (0.3 deg) and stops.
    """
    a, t = opening_half, 0.02
    base = mocap_body(spec, name)
    # Frame: two posts and a lintel, their front faces at x = 0, on a base plate.
    add_geom(base, f"{name}/plate", "box", [0.075, a + POST + 0.04, 0.005], WOOD,
             pos=[-0.075, 0, 0.005])
    for sy, part in ((-1, "hinge_post"), (1, "strike_post")):
        add_geom(base, f"{name}/{part}", "box", [POST / 2, POST / 2, height / 2], WOOD,
                 pos=[-POST / 2, sy * (a + POST / 2), 0.01 + height / 2])
    add_geom(base, f"{name}/lintel", "box", [POST / 2, a + POST, POST / 2], WOOD,
             pos=[-POST / 2, 0, 0.01 + height + POST / 2])
    # The door overlays the posts by 2 cm on each side.
    width, z0, z1 = 2 * a + 0.04, 0.012, 0.01 + height
    door = base.add_body(name=f"{name}/door", pos=[GAP, -a - 0.02, 0.0])
    add_joint(door, f"{name}/door", "hinge", (0, 0, -1), (0.0, swing), 0.3, 0.2,
              armature=0.01)
    add_geom(door, f"{name}/door", "box", [t / 2, width / 2, (z1 - z0) / 2], WOOD, 1.3,
             pos=[t / 2, width / 2, (z0 + z1) / 2])
    # Lever: on a spindle normal to the door (axis -x: positive lifts its free end).
    spindle_y, handle_z = width - 0.02 - SPINDLE_IN, z0 + 0.55 * (z1 - z0)
    lever = door.add_body(name=f"{name}/lever", pos=[0.0, spindle_y, handle_z])
    lever.add_joint(name=f"{name}/lever", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[-1, 0, 0],
                    range=[0.0, LEVER_TRAVEL], damping=0.02, armature=1e-3,
                    stiffness=LEVER_SPRING, springref=-LEVER_PRELOAD)
    front = t + LEVER_OUT
    add_geom(lever, f"{name}/lever_neck", "capsule", [0.008, LEVER_OUT / 2], DARK, 0.02,
             pos=[t + LEVER_OUT / 2, 0, 0], quat=[0.7071068, 0, 0.7071068, 0])
    add_geom(lever, f"{name}/lever", "capsule", [0.009, LEVER_LENGTH / 2], DARK, 0.08,
             pos=[front, -LEVER_LENGTH / 2, 0], quat=[0.7071068, 0.7071068, 0, 0])
    add_visual(lever, f"{name}/rose", "cylinder", [0.022, 0.004], DARK,
               pos=[t + 0.004, 0, 0], quat=[0.7071068, 0, 0.7071068, 0])
    back = -GAP - POST - 0.002 - CAM_HALF[0]  # the cam's middle, behind the post's back face
    add_visual(lever, f"{name}/spindle", "box", [(t - back) / 2, 0.004, 0.004], DARK,
               pos=[(t + back) / 2, 0, 0])
    reach = SPINDLE_IN + CAM_OVER  # from the spindle to the cam's tip
    add_geom(lever, f"{name}/cam", "box", [CAM_HALF[0], reach / 2, CAM_HALF[1]], DARK, 0.005,
             pos=[back, reach / 2, 0])
    return ObjectInfo(name, name, None, True, 0.0, float(math.hypot(0.15, a + POST + 0.04)),
                      joints={f"{name}/door": (0.0, swing), f"{name}/lever": (0.0, LEVER_TRAVEL)},
                      points={"handle": (f"{name}/lever", (front, -GRIP, 0.0)),
                              "latch": (f"{name}/lever", (back, reach, 0.0))})


def add_double_door_cabinet(spec: mujoco.MjSpec, name: str,
                            size: tuple[float, float, float] = (0.16, 0.24, 0.18),
                            opening: float = math.radians(100.0)) -> ObjectInfo:
    """A tabletop cupboard (0.32 x 0.48 x 0.36 m) with two overlay doors meeting in the
    middle (3 mm apart), hinged at its -y and +y edges, each opening up to `opening`:
    joints `<name>/a/door` (hinged at -y) and `<name>/b/door` (at +y), points `handle_a`
    and `handle_b`. Each 16 mm particle-board door weighs 0.9 kg; hinges as the one-door
    cupboard's (damping 0.2 N m s/rad, friction loss 0.15 N m)."""
    hx, hy, hz = size
    base = mocap_body(spec, name)
    _carcass(base, name, hx, hy, hz, 0.01, WOOD)
    add_geom(base, f"{name}/shelf", "box", [hx - 0.02, hy - 0.02, 0.008], WOOD,
             pos=[0, 0, hz])
    width = hy - 0.0015
    joints, points = {}, {}
    for key, side in (("a", 1.0), ("b", -1.0)):
        joint, handle = _door(base, f"{name}/{key}", "door", (hx, -side * hy), width,
                              (0.005, 2 * hz), 0.016, 0.9, opening, 0.2, 0.15, WOOD, hz * 1.2,
                              side=side)
        joints[joint] = (0.0, opening)
        points[f"handle_{key}"] = (f"{name}/{key}/door", handle)
    return ObjectInfo(name, name, None, True, 0.0, float(math.hypot(hx, hy)),
                      joints=joints, points=points)
