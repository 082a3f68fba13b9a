"""Folding hand-held things: a pair of glasses (two temple arms on hinges) and a tri-fold
phone (three panels on two hinges).

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


PHONE_FRAME = (0.55, 0.56, 0.58, 1.0)  # titanium-grey frame and back
SCREEN = (0.03, 0.04, 0.06, 1.0)
PHONE_THICKNESS = (0.00475, 0.0036, 0.0036)  # m, bottom (camera) panel to top


def add_trifold_phone(spec: mujoco.MjSpec, name: str, panel: tuple[float, float] = (0.157, 0.073),
                      thickness: tuple[float, float, float] = PHONE_THICKNESS,
                      masses: tuple[float, float, float] = (0.118, 0.09, 0.09),
                      friction: float = 0.03) -> ObjectInfo:
    """A Z-folding tri-fold phone, a Huawei Mate XT (157 x 219 mm unfolded, 298 g):
    three `panel` (length along x, width along y) panels, bottom to top `thickness`
    thick (the camera panel 4.75 mm, the others 3.6 mm) and `masses` heavy (the 298 g
    shared by thickness: the thick one carries cameras and main board), folded flat.

    The root is the bottom (camera) panel, the base, lying on the table (frame at the
    middle of its underside). Joint `<name>/hinge1` (at the base's +y edge) carries the
    middle panel, folded onto the base's screen (an inward fold); joint `<name>/hinge2`
    (at the middle panel's far, -y, edge) carries the top panel, folded back over the
    middle one's outside (an outward fold: its screen faces up, the folded phone's
    front). Both run from 0 (folded) to 180 deg (flat: the three screens make one).
    Opening hinge 1 lifts the middle panel's -y end off the base; opening hinge 2 lifts
    the top panel's +y end off the middle one. Each pivot is on the faces the hinge
    folds together, so folded the panels stack and open their screens lie in one plane.
    Friction loss `friction` holds a 90 g panel raised 25 deg or more (its weight:
    0.032 N m held out flat), yet is less than the base's weight about its own edge
    (0.042 N m): lifting the upper panels turns the hinge rather than tipping the base.
    Points: `edge2` (middle of the top panel's free edge, on its underside), `end1`
    (middle of the middle panel's free edge, on its underside), `screen` (the base's
    top face, middle). Axes: `up`, `hinge` (along the hinge lines).
    """
    hx, hy = panel[0] / 2, panel[1] / 2
    base = free_body(spec, name)

    def slab(body: mujoco.MjsBody, k: int, cy: float, screen_up: bool) -> None:
        """Panel `k`, from y = cy - hy to cy + hy and z = 0 up, its screen up or down."""
        key, t = ("base", "middle", "top")[k], thickness[k]
        add_geom(body, f"{name}/{key}", "box", [hx, hy, t / 2], PHONE_FRAME, masses[k],
                 pos=[0.0, cy, t / 2])
        add_visual(body, f"{name}/{key}_screen", "box", [hx - 0.002, hy - 0.002, 1e-4],
                   SCREEN, pos=[0.0, cy, t + 1e-4 if screen_up else -1e-4])

    slab(base, 0, 0.0, True)
    middle = base.add_body(name=f"{name}/middle", pos=[0.0, hy, thickness[0]])
    hinge1 = add_joint(middle, f"{name}/hinge1", "hinge", (-1.0, 0.0, 0.0), (0.0, math.pi),
                       0.005, friction)
    slab(middle, 1, -hy, False)
    top = middle.add_body(name=f"{name}/top", pos=[0.0, -2 * hy, thickness[1]])
    hinge2 = add_joint(top, f"{name}/hinge2", "hinge", (1.0, 0.0, 0.0), (0.0, math.pi),
                       0.005, friction)
    slab(top, 2, hy, True)
    joints = {hinge1: (0.0, math.pi), hinge2: (0.0, math.pi)}
    points = {"edge2": (top.name, (0.0, 2 * hy, 0.0)),
              "end1": (middle.name, (0.0, -2 * hy, 0.0)),
              "screen": (name, (0.0, 0.0, thickness[0]))}
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, math.hypot(hx, hy + 0.01),
                      joints=joints, points=points,
                      axes={"up": (name, UP), "hinge": (name, (1.0, 0.0, 0.0))})
