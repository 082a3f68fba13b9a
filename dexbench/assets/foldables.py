"""Folding hand-held things: a pair of glasses (two temple arms on hinges).

Like `office`, their hinges open towards positive angles from 0 (folded), with friction
loss that holds a part at any angle against its own weight (`parts.add_joint`).
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.objects import UP, ObjectInfo, add_geom, free_body
from dexbench.assets.parts import add_joint, add_visual

FRAME = (0.12, 0.1, 0.09, 1.0)  # dark tortoiseshell acetate
LENS = (0.75, 0.85, 0.9, 0.45)


def add_glasses(spec: mujoco.MjSpec, name: str, width: float = 0.14,
                temple: float = 0.135, open_limit: float = math.radians(95.0),
                mass: float = 0.036) -> ObjectInfo:
    """A pair of glasses (front `width` wide, temples `temple` long, 36 g with its
    lenses: an acetate frame with two glass lenses, 5 g a temple) lying on the
    outside of its front, the temples folded on top: the front spans y, its top edge
    towards +x.

    Joints `<name>/temple_a` (hinged at the +y end, folds towards -y) and
    `<name>/temple_b` (at the -y end, folds towards +y) run from 0 (folded, parallel to
    the front) to `open_limit` (the end piece's stop, a little past square); opening
    swings a temple up off the front. The hinges are staggered 24 mm apart across the
    front's height (temple a nearer its top, +x): folded, the two temples then lie side
    by side instead of crossing (real temples cross, bent to lie one over the other).
    Friction loss 0.005 N m (a screwed hinge) beats a temple's weight (at most
    0.0033 N m), and lifting a temple barely tips the front over its hinge end.
    Points: `tip_a` / `tip_b` (the underside of each temple's free end), `bridge` (the
    front's middle, on top). Axes: `up`, `temple_a` / `temple_b` (the free ends'
    directions).
    """
    half, lens_r, lens_t = width / 2, 0.024, 0.002
    lens_y = half - 0.004 - lens_r  # the rims reach the end pieces
    body = free_body(spec, name)
    front_mass = mass - 2 * 0.005
    for sy in (1, -1):  # the rims with their lenses, flat on the table
        add_geom(body, f"{name}/rim{sy}", "cylinder", [lens_r, lens_t], FRAME,
                 0.4 * front_mass, pos=[0.0, sy * lens_y, lens_t])
        add_visual(body, f"{name}/lens{sy}", "cylinder", [lens_r - 0.003, lens_t + 2e-4],
                   LENS, pos=[0.0, sy * lens_y, lens_t])
    add_geom(body, f"{name}/bridge", "box", [0.004, lens_y - lens_r + 0.002, lens_t], FRAME,
             0.05 * front_mass, pos=[0.01, 0.0, lens_t])
    hinge_z, ta, tt = 0.012, 0.0025, 0.0015  # temple: half height (along x), half thickness
    stagger = 0.012
    joints, points, axes = {}, {}, {"up": (name, UP)}
    for key, sy, sx in (("a", 1, 1), ("b", -1, -1)):
        # The end piece: from the rim's outer edge up to the hinge, behind the front.
        add_geom(body, f"{name}/end_{key}", "box", [0.005, 0.004, hinge_z / 2], FRAME,
                 0.075 * front_mass, pos=[sx * stagger, sy * (half - 0.004), hinge_z / 2])
        arm = body.add_body(name=f"{name}/temple_{key}", pos=[sx * stagger, sy * half, hinge_z])
        joint = add_joint(arm, f"{name}/temple_{key}", "hinge", (-sy, 0.0, 0.0),
                          (0.0, open_limit), 0.002, 0.005)
        add_geom(arm, f"{name}/temple_{key}", "box", [ta, temple / 2, tt], FRAME, 0.005,
                 pos=[0.0, -sy * temple / 2, 0.0])
        joints[joint] = (0.0, open_limit)
        points[f"tip_{key}"] = (arm.name, (0.0, -sy * (temple - 0.012), -tt))
        axes[f"temple_{key}"] = (arm.name, (0.0, -sy, 0.0))
    points["bridge"] = (name, (0.0, 0.0, 2 * lens_t))
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, math.hypot(half, lens_r),
                      joints=joints, points=points, axes=axes)
