"""Containers carried by hand: a cast-iron Dutch oven with two loop handles and a woven
basket with a rolled rim (both lifted in two hands), and a shopping basket with two
folding handles.

All stand with their bottom at the body origin (`rest_height` 0); axis `up` is their
vertical. The first two have their grips on opposite sides, points `grip_ypos` /
`grip_yneg` (the Dutch oven's handle bars, the middles of the basket's short walls), as
the tray and carton do (`objects.add_tray`, `kitchen.add_carton`), for `TwoHandPlan` to
hook.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.meshes import add_lathe_object
from dexbench.assets.objects import UP, ObjectInfo, add_geom, free_body
from dexbench.assets.parts import add_joint, add_visual

CAST_IRON = (0.55, 0.12, 0.1, 1.0)  # red enamel outside



def _open_box(body: mujoco.MjsBody, name: str, half: tuple[float, float, float], wall: float,
              floor: float, rgba: tuple[float, float, float, float], mass: float) -> None:
    """A floor (half-thickness `floor`) and four walls (half-thickness `wall`) of an open
    box of half-extents `half`, sharing `mass` by volume."""
    hx, hy, hz = half
    walls = {"floor": ((hx, hy, floor), (0.0, 0.0, floor)),
             "xpos": ((wall, hy, hz), (hx - wall, 0.0, hz)),
             "xneg": ((wall, hy, hz), (-hx + wall, 0.0, hz)),
             "ypos": ((hx - 2 * wall, wall, hz), (0.0, hy - wall, hz)),
             "yneg": ((hx - 2 * wall, wall, hz), (0.0, -hy + wall, hz))}
    volume = sum(a * b * c for (a, b, c), _ in walls.values())
    for part, (size, pos) in walls.items():
        add_geom(body, f"{name}/{part}", "box", size, rgba,
                 mass * size[0] * size[1] * size[2] / volume, pos=pos)

def add_dutch_oven(spec: mujoco.MjSpec, name: str, radius: float = 0.105,
                   height: float = 0.10, mass: float = 2.4) -> ObjectInfo:
    """A round enamelled cast-iron Dutch oven without its lid (21 cm across, 10 cm tall,
    2.4 kg: a 2.5 l pot's body; the lid, another kilogram, is not part of the task).

    Walls 6 mm, bottom 7 mm. Two cast loop handles at +-y, level with the rim (as on
    the common enamelled ovens): a bar (1.6 cm thick, 11 cm long) on two arms, 3 cm clear
    of the wall. Points `grip_ypos` / `grip_yneg` are the bars' middles.
    """
    gap, bar_r, half_len = 0.03, 0.008, 0.055
    handle_z = height - bar_r
    handle_mass = 0.1
    body = add_lathe_object(spec, name, [(radius - 0.01, 0.0), (radius, 0.012),
                                         (radius, height)], 0.006, mass - 2 * handle_mass,
                            CAST_IRON, bottom_thickness=0.007)
    bar_y = radius + gap + bar_r
    # Where the arms meet the wall: the circle at +-half_len along x.
    foot_y = math.sqrt(radius**2 - half_len**2) - 0.003
    for sy in (1, -1):
        add_geom(body, f"{name}/handle{sy}_bar", "capsule", [bar_r], CAST_IRON,
                 0.5 * handle_mass,
                 fromto=[-half_len, sy * bar_y, handle_z, half_len, sy * bar_y, handle_z])
        for sx in (1, -1):
            add_geom(body, f"{name}/handle{sy}_arm{sx}", "capsule", [bar_r], CAST_IRON,
                     0.25 * handle_mass, fromto=[sx * half_len, sy * foot_y, handle_z,
                                                 sx * half_len, sy * bar_y, handle_z])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, bar_y + bar_r,
                      points={"grip_ypos": (name, (0.0, bar_y, handle_z)),
                              "grip_yneg": (name, (0.0, -bar_y, handle_z))},
                      axes={"up": (name, UP)})


WICKER = (0.72, 0.55, 0.32, 1.0)
WICKER_DARK = (0.6, 0.44, 0.24, 1.0)


def add_basket(spec: mujoco.MjSpec, name: str, half: tuple[float, float, float] = (
        0.12, 0.18, 0.07), mass: float = 0.6) -> ObjectInfo:
    """An open woven basket (24 x 36 x 14 cm, 0.6 kg of willow), long along y, with a
    rolled rim (a 1.2 cm thick band round the top) that hands hook over at its short
    (+-y) ends, as one carries a basket in front of oneself.

    Walls 8 mm, floor 10 mm; the rim is a capsule along each top edge. Points
    `grip_ypos` / `grip_yneg` are the short walls' middles, 1.5 cm below the rim's top.
    """
    hx, hy, hz = half
    t, rim = 0.004, 0.006  # half the wall's thickness; the rim's radius
    body = free_body(spec, name)
    _open_box(body, name, half, t, 0.005, WICKER, 0.85 * mass)
    top = 2 * hz
    corners = [(hx - t, hy - t), (-hx + t, hy - t), (-hx + t, -hy + t), (hx - t, -hy + t)]
    for k in range(4):
        (x0, y0), (x1, y1) = corners[k], corners[(k + 1) % 4]
        add_geom(body, f"{name}/rim{k}", "capsule", [rim], WICKER_DARK, 0.15 * mass / 4,
                 fromto=[x0, y0, top - rim, x1, y1, top - rim])
    for k, z in enumerate((0.35 * top, 0.65 * top)):  # woven bands, decoration
        add_visual(body, f"{name}/band{k}", "box", [hx + 5e-4, hy + 5e-4, 0.006],
                   WICKER_DARK, pos=[0.0, 0.0, z])
    grip_z = top - 0.015
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, float(math.hypot(hx, hy)),
                      points={"grip_ypos": (name, (0.0, hy - t, grip_z)),
                              "grip_yneg": (name, (0.0, -hy + t, grip_z))},
                      axes={"up": (name, UP)})


BASKET_RED = (0.8, 0.15, 0.15, 1.0)
BASKET_BLACK = (0.12, 0.12, 0.13, 1.0)
WIRE_GREY = (0.6, 0.6, 0.62, 1.0)


def add_shopping_basket(spec: mujoco.MjSpec, name: str, half: tuple[float, float, float] = (
        0.14, 0.20, 0.09), mass: float = 0.5, rest: float = math.radians(100.0)
        ) -> ObjectInfo:
    """A plastic shopping basket (28 x 40 x 18 cm, 0.5 kg of polypropylene), long along
    y, with two carrying handles: steel-wire U's (60 g, a plastic grip tube in the
    middle) whose arms pivot on the short (+-y) walls 3 cm in from the long walls.

    Upright (0) the two handles meet over the basket; each folds outward over its long
    wall to a stop lug `rest` from upright, where it sticks out a little below the
    horizontal. Joint `handle0` folds to -x (negative angles), `handle1` to +x (its
    axis is -y, so it too folds to negative angles): both range over [-rest, 0].
    Damping 0.005 N m s/rad and friction loss 0.005 N m, as the bucket's bail: a wire in
    a moulded pivot swings freely. Points `grip0` / `grip1` are the grip tubes'
    undersides when folded (their local -x).
    """
    hx, hy, hz = half
    t = 0.003  # half the wall's thickness
    body = free_body(spec, name)
    _open_box(body, name, half, t, t, BASKET_RED, mass)
    arm, grip_r, span = 0.16, 0.011, hy + 0.006
    joints, points = {}, {}
    for k, sx in enumerate((-1, 1)):
        handle = body.add_body(name=f"{name}/handle{k}_body",
                               pos=[sx * (hx - 0.03), 0.0, 2 * hz - 0.01])
        joint = add_joint(handle, f"{name}/handle{k}", "hinge", (0, -sx, 0), (-rest, 0.0),
                          0.005, 0.005)
        for sy in (1, -1):
            add_geom(handle, f"{name}/handle{k}_arm{sy}", "capsule", [0.0025], WIRE_GREY,
                     0.01, fromto=[0, sy * span, 0, 0, sy * span, arm])
        add_geom(handle, f"{name}/handle{k}_bar", "capsule", [0.0025], WIRE_GREY, 0.01,
                 fromto=[0, -span, arm, 0, span, arm])
        add_geom(handle, f"{name}/handle{k}_grip", "capsule", [grip_r], BASKET_BLACK, 0.03,
                 fromto=[0, -0.06, arm, 0, 0.06, arm])
        joints[joint] = (-rest, 0.0)
        points[f"grip{k}"] = (f"{name}/handle{k}_body", (sx * grip_r, 0.0, arm))
    return ObjectInfo(name, name, f"{name}/free", False, 0.0,
                      float(math.hypot(hx - 0.03 + arm, hy)), joints=joints, points=points,
                      axes={"up": (name, UP)})
