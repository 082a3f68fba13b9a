"""Containers with a lid hinged at the back: a wooden storage box and a cooking pot.

Like the laptop (`articulated.add_laptop`), the hinge runs along the object's +x edge
and the front, with the tab a hand lifts the lid by, faces -x: at yaw 0 it faces the
robot. The lid's hinge opens with positive angles from 0 (closed, resting on the rim:
the lower limit stands for that contact, as parent and child bodies do not collide) to
its upper stop. Both are free bodies on the table: their own weight holds them down while
one hand lifts the lid, and there is no spring, so a lid falls back shut unless pushed
past upright. Points: `tab` (under the front tab's free edge), `lid_centre`.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.meshes import add_lathe_object
from dexbench.assets.objects import ObjectInfo, add_geom, free_body
from dexbench.assets.parts import add_joint

WOOD = (0.62, 0.45, 0.28, 1.0)
LID_WOOD = (0.55, 0.38, 0.22, 1.0)
STEEL = (0.75, 0.75, 0.78, 1.0)
GLASS = (0.7, 0.8, 0.85, 0.6)
BLACK = (0.1, 0.1, 0.1, 1.0)
GAP = 0.001  # m between the closed lid and the rim it rests on: no contact at reset


def add_storage_box(spec: mujoco.MjSpec, name: str, half: tuple[float, float, float] = (
        0.11, 0.15, 0.065), mass: float = 1.0, lid_mass: float = 0.45,
        open_angle: float = math.radians(105.0)) -> ObjectInfo:
    """A wooden storage box (22 x 30 x 13 cm, 8 mm plywood walls) with a hinged lid.

    Masses are plywood's (about 600 kg/m3): 1 kg of walls, a 0.45 kg lid (12 mm). The
    lid has a 25 mm tab sticking out over the front wall for fingers to lift it by. Its
    hinges (plain butt hinges) have a little damping and friction (0.03 N m s, 0.02 N m):
    the lid (about 0.5 N m of weight torque when closed) falls shut if let go before
    upright, and the box's weight holds it down while one hand lifts the lid. The lid
    stops at `open_angle`, leaning back on its hinges.
    """
    hx, hy, hz = half
    t = 0.008
    body = free_body(spec, name)
    walls = {"floor": ((hx, hy, t / 2), (0, 0, t / 2)),
             "front": ((t / 2, hy, hz), (-hx + t / 2, 0, hz)),
             "back": ((t / 2, hy, hz), (hx - t / 2, 0, hz)),
             "left": ((hx - t, t / 2, hz), (0, hy - t / 2, hz)),
             "right": ((hx - t, t / 2, hz), (0, -hy + t / 2, hz))}
    volume = sum(a * b * c for (a, b, c), _ in walls.values())
    for part, (size, pos) in walls.items():
        add_geom(body, f"{name}/{part}", "box", size, WOOD,
                 mass * size[0] * size[1] * size[2] / volume, pos=pos)
    lid = body.add_body(name=f"{name}/lid", pos=[hx, 0, 2 * hz + GAP])
    joint = add_joint(lid, f"{name}/hinge", "hinge", (0, 1, 0), (0.0, open_angle), 0.03,
                      0.02)
    lt = 0.006  # half the lid's thickness
    add_geom(lid, f"{name}/lid", "box", [hx + 0.003, hy + 0.003, lt], LID_WOOD,
             0.95 * lid_mass, pos=[-hx, 0, lt])
    tab = 0.025
    add_geom(lid, f"{name}/tab", "box", [tab / 2, 0.035, 0.004], LID_WOOD, 0.05 * lid_mass,
             pos=[-2 * hx - 0.003 - tab / 2, 0, 0.004])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, float(math.hypot(hx + tab, hy)),
                      joints={joint: (0.0, open_angle)},
                      points={"tab": (f"{name}/lid", (-2 * hx - tab + 0.005, 0.0, 0.0)),
                              "lid_centre": (f"{name}/lid", (-hx, 0.0, 2 * lt))})


def add_lidded_pot(spec: mujoco.MjSpec, name: str, radius: float = 0.10,
                   height: float = 0.11, mass: float = 1.1, lid_mass: float = 0.4,
                   open_angle: float = math.radians(110.0)) -> ObjectInfo:
    """A 20 cm stainless cooking pot with two side grips and a glass lid hinged at its
    back rim, a knob in the middle of the lid and a thumb tab at its front.

    The lid hinge (a steel bracket pin) has light damping and friction (0.03 N m s,
    0.02 N m); the lid's weight (about 0.4 N m when closed) shuts it if let go before
    upright, and the pot's own weight (1.1 kg) holds it down as one hand lifts the lid.
    """
    wall = 0.003
    body = add_lathe_object(spec, name, [(radius, 0.0), (radius, height)], wall, mass, STEEL,
                            bottom_thickness=0.005)
    for sy in (1, -1):
        add_geom(body, f"{name}/grip{sy}", "capsule", [0.008], BLACK, 0.03,
                 fromto=[-0.03, sy * (radius + 0.022), height - 0.02,
                         0.03, sy * (radius + 0.022), height - 0.02])
        for sx in (1, -1):
            add_geom(body, f"{name}/grip{sy}_post{sx}", "box", [0.005, 0.013, 0.005], BLACK,
                     0.005, pos=[sx * 0.025, sy * (radius + 0.011), height - 0.02])
    add_geom(body, f"{name}/bracket", "box", [0.008, 0.02, 0.01], STEEL, 0.02,
             pos=[radius + 0.006, 0, height - 0.008])
    r = radius + 0.004  # the lid overhangs the rim a little
    lid = body.add_body(name=f"{name}/lid", pos=[radius + 0.006, 0, height + GAP])
    joint = add_joint(lid, f"{name}/hinge", "hinge", (0, 1, 0), (0.0, open_angle), 0.03, 0.02)
    lt = 0.0025  # half the glass's thickness
    centre = -(radius + 0.006)
    add_geom(lid, f"{name}/lid", "cylinder", [r, lt], GLASS, 0.8 * lid_mass,
             pos=[centre, 0, lt])
    add_geom(lid, f"{name}/knob", "cylinder", [0.016, 0.01], BLACK, 0.12 * lid_mass,
             pos=[centre, 0, 2 * lt + 0.01])
    tab = 0.025
    front = centre - r
    add_geom(lid, f"{name}/tab", "box", [tab / 2, 0.025, 0.003], BLACK, 0.08 * lid_mass,
             pos=[front - tab / 2 + 0.004, 0, 0.003])
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, radius + 0.035,
                      joints={joint: (0.0, open_angle)},
                      points={"tab": (f"{name}/lid", (front - tab + 0.009, 0.0, 0.0)),
                              "lid_centre": (f"{name}/lid", (centre, 0.0, 2 * lt))})
