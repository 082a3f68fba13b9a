"""A hammer, the stand it is stored on, and a board with a nail to drive in.

The hammer is stored standing on its striking face with its handle in a cradle, which
keeps the handle 3.6 cm off the table for the fingers. The nail is a slide joint with
friction loss: a strike or a firm press (more than 15 N) drives it, nothing less does.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.objects import UP, ObjectInfo, Zone, add_geom, free_body, mocap_body
from dexbench.assets.parts import add_joint, zone_body

WOOD = (0.78, 0.58, 0.34, 1.0)
STAND = (0.3, 0.3, 0.32, 1.0)
STEEL = (0.45, 0.47, 0.5, 1.0)
HANDLE_HALF = (0.1, 0.011, 0.014)  # the hammer handle's half extents
HEAD_RADIUS, HEAD_HALF = 0.016, 0.05
CRADLE_X = -0.07  # where the stand holds the handle, in the hammer's frame
# The nail's 15 N friction would stop a 16 g nail within one step, and the solver then
# chatters it up and down; 0.2 kg of armature (the wood it drags) lets it settle.
NAIL_ARMATURE = 0.2


def add_hammer(spec: mujoco.MjSpec, name: str, mass: float = 0.32) -> ObjectInfo:
    """A club hammer: a wooden handle along +x and a steel head across its +x end.

    The head is a cylinder along z (78% of the mass); its -z end is the striking face.
    The hammer stands on it with its handle in `add_hammer_stand`'s cradle (`rest_height`
    is the face's depth below the handle axis); without the stand it tips onto its butt.
    Points: `grip` (handle, 6 cm from its butt), `face` (centre of the striking face),
    `head`. Axes: `handle` (butt to head), `strike` (out of the face).
    """
    body = free_body(spec, name)
    hx, hy, hz = HANDLE_HALF
    add_geom(body, f"{name}/handle", "box", [hx, hy, hz], WOOD, 0.22 * mass)
    head_x = hx + 0.005
    add_geom(body, f"{name}/head", "cylinder", [HEAD_RADIUS, HEAD_HALF], STEEL, 0.78 * mass,
             pos=[head_x, 0, 0])
    return ObjectInfo(name, name, f"{name}/free", False, HEAD_HALF, head_x + HEAD_RADIUS,
                      points={"grip": (name, (-hx + 0.06, 0.0, 0.0)),
                              "face": (name, (head_x, 0.0, -HEAD_HALF)),
                              "head": (name, (head_x, 0.0, 0.0))},
                      axes={"handle": (name, (1.0, 0.0, 0.0)),
                            "strike": (name, (0.0, 0.0, -1.0))})


def add_hammer_stand(spec: mujoco.MjSpec, name: str) -> ObjectInfo:
    """The cradle (fixed) that holds an `add_hammer` hammer's handle near its butt.

    Point `hammer` is where the hammer's root goes for it to stand on its face with the
    handle in the cradle, the hammer turned like the stand (its +x along the stand's +x).
    """
    base = mocap_body(spec, name)
    saddle = HEAD_HALF - HANDLE_HALF[2]
    add_geom(base, f"{name}/saddle", "box", [0.015, 0.025, saddle / 2], STAND,
             pos=[0, 0, saddle / 2])
    post_y = HANDLE_HALF[1] + 0.002 + 0.004
    for k, y in enumerate((post_y, -post_y)):
        add_geom(base, f"{name}/post{k}", "box", [0.015, 0.004, 0.012], STAND,
                 pos=[0, y, saddle + 0.012])
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(0.015, 0.025),
                      points={"hammer": (name, (-CRADLE_X, 0.0, HEAD_HALF))})


def add_nail_board(spec: mujoco.MjSpec, name: str, proud: float = 0.07,
                   friction: float = 15.0) -> ObjectInfo:
    """A wooden block (fixed, 8 cm tall) with a nail standing `proud` out of its top.

    Joint `<name>/nail` slides along z: 0 at reset, -(proud - 2 mm) driven home; the
    driven depth is minus the joint value. Friction loss `friction` (N) and damping
    make one blow drive it 1-2 cm (a 0.32 kg hammer at 1.5 m/s); a steady press below
    the friction creeps it about 2 mm/s (friction loss is soft in MuJoCo). The head (body
    `<name>/nail_head`, 8 mm tall so a face moving 2 m/s cannot step through it in one
    timestep) is the no-touch part. Points: `nail_head` (top of the head), `board_top`.
    """
    base = mocap_body(spec, name)
    top = 0.08
    add_geom(base, f"{name}/block", "box", [0.07, 0.07, top / 2], WOOD, pos=[0, 0, top / 2])
    nail = base.add_body(name=f"{name}/nail", pos=[0, 0, top])
    depth = proud - 0.002
    joint = add_joint(nail, f"{name}/nail", "slide", UP, (-depth, 0.0), 5.0, friction,
                      armature=NAIL_ARMATURE)
    buried = 0.003  # driven home, the nail's tip stays inside the block
    add_geom(nail, f"{name}/shank", "cylinder", [0.003, (proud + buried) / 2], STEEL, 0.01,
             pos=[0, 0, (proud - buried) / 2])
    head = zone_body(nail, f"{name}/nail_head", (0.0, 0.0, proud))
    half = 0.004
    add_geom(head, f"{name}/nail_head", "cylinder", [0.012, half], STEEL, 0.006,
             pos=[0, 0, half])
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(0.07, 0.07),
                      joints={joint: (-depth, 0.0)},
                      points={"nail_head": (f"{name}/nail_head", (0.0, 0.0, 2 * half)),
                              "board_top": (name, (0.0, 0.0, top))},
                      axes={"up": (name, UP)},
                      zones=(Zone(f"{name}/nail_head", "cylinder", (0.0, 0.0, half), 0.017,
                                  half + 0.005),))
