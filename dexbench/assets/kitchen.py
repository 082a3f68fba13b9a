"""Kitchen objects: a frying pan and its stove, a cup rack, and a carton for two hands.

Free objects rest on their bottom at the body origin (`rest_height` 0) except the carton
(a box, origin at its bottom too). Fixed ones (stove, rack) are mocap bodies placed per
environment. Handles point along +x in the object's frame; tasks turn them at reset.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco

from dexbench.assets.meshes import add_lathe_object, radius_at
from dexbench.assets.objects import UP, ObjectInfo, Zone, add_geom, free_body, mocap_body
from dexbench.assets.parts import add_visual, zone_body

IRON = (0.25, 0.25, 0.27, 1.0)
COATING = (0.08, 0.08, 0.09, 1.0)
ENAMEL = (0.9, 0.9, 0.88, 1.0)
CARDBOARD = (0.72, 0.55, 0.36, 1.0)
Z90 = [math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)]  # quarter turn about z


def add_pan(spec: mujoco.MjSpec, name: str, radius: float = 0.10, depth: float = 0.035,
            handle_length: float = 0.17, mass: float = 0.3) -> ObjectInfo:
    """A frying pan (flared wall, `radius` at the rim) with a long handle along +x.

    The handle is a 2.2 cm thick capsule rising 25 deg from the rim, like a real pan's: its
    outer half is high enough off the table for fingers to close under it. The non-stick
    floor disc (body `<name>/surface`) is the cooking surface a hand must not touch.
    Points: `centre` (bottom centre, what sits on a burner),
    `handle` (middle of the handle), `handle_end`. Axes: `up`, `handle` (rim to end).
    """
    wall, floor = 0.004, 0.005
    profile = [(0.85 * radius, 0.0), (radius, depth)]
    body = add_lathe_object(spec, name, profile, wall, 0.72 * mass, IRON,
                            bottom_thickness=floor)
    surface = zone_body(body, f"{name}/surface", (0.0, 0.0, floor))
    inner = radius_at(profile, floor) - wall - 0.002
    add_geom(surface, f"{name}/surface", "cylinder", [inner, 0.001], COATING, 0.03 * mass,
             pos=[0, 0, 0.001])
    pitch = math.radians(25.0)
    start = (radius + 0.002, 0.0, depth - 0.008)
    end = (start[0] + handle_length * math.cos(pitch), 0.0,
           start[2] + handle_length * math.sin(pitch))
    bar_r = 0.011
    add_geom(body, f"{name}/handle", "capsule", [bar_r], COATING, 0.25 * mass,
             fromto=[*start, *end])
    axis = (math.cos(pitch), 0.0, math.sin(pitch))
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, end[0] + bar_r,
                      points={"centre": (name, (0.0, 0.0, 0.0)),
                              "handle": (name, tuple((a + b) / 2 for a, b in
                                                     zip(start, end, strict=True))),
                              "handle_end": (name, end)},
                      axes={"up": (name, UP), "handle": (name, axis)},
                      zones=(Zone(f"{name}/surface", "cylinder", (0.0, 0.0, 0.001),
                                  inner, 0.006),))


def add_stove(spec: mujoco.MjSpec, name: str, half: Sequence[float] = (0.15, 0.15, 0.02)
              ) -> ObjectInfo:
    """A one-burner stove top (fixed): an enamel slab with a cross-shaped grate.

    A pan rests on the grate bars; point `target` is the grate's top centre, where a
    pan's `centre` sits when it is centred on the burner. Axis `up`.
    """
    hx, hy, hz = half
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/slab", "box", [hx, hy, hz], ENAMEL, pos=[0, 0, hz])
    add_geom(base, f"{name}/burner", "cylinder", [0.045, 0.003], IRON,
             pos=[0, 0, 2 * hz + 0.003])
    bar = [0.085, 0.006, 0.006]
    top = 2 * hz + 2 * bar[2]
    add_geom(base, f"{name}/grate0", "box", bar, COATING, pos=[0, 0, top - bar[2]])
    add_geom(base, f"{name}/grate1", "box", bar, COATING, pos=[0, 0, top - bar[2]], quat=Z90)
    for k, y in enumerate((-0.6 * hy, 0.6 * hy)):
        add_geom(base, f"{name}/knob{k}", "cylinder", [0.012, 0.008], COATING,
                 pos=[hx + 0.008, y, hz], quat=[math.sqrt(0.5), 0, math.sqrt(0.5), 0])
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(hx + 0.016, hy),
                      points={"target": (name, (0.0, 0.0, top))}, axes={"up": (name, UP)})


def add_cup_rack(spec: mujoco.MjSpec, name: str, shelf_height: float = 0.08,
                 cup_radius: float = 0.035, rod_height: float = 0.06) -> ObjectInfo:
    """A cup stand (fixed): a raised shelf on a post with four retaining rods.

    A cup of rim radius up to `cup_radius` stands on the shelf inside the rods and must be
    lifted `rod_height` before it can leave sideways; the gaps between rods (5.4 cm) let
    fingers in but not the cup out. One gap faces +x.
    Points: `slot` (shelf top centre, where the cup's bottom stands), `top` (rod tops).
    """
    base = mocap_body(spec, name)
    wood = (0.55, 0.38, 0.22, 1.0)
    add_geom(base, f"{name}/foot", "cylinder", [0.07, 0.005], wood, pos=[0, 0, 0.005])
    add_geom(base, f"{name}/post", "cylinder", [0.012, shelf_height / 2], wood,
             pos=[0, 0, shelf_height / 2])
    shelf_r = cup_radius + 0.02
    add_geom(base, f"{name}/shelf", "cylinder", [shelf_r, 0.005], wood,
             pos=[0, 0, shelf_height - 0.005])
    rod_r, ring = 0.004, cup_radius + 0.009
    for k in range(4):
        a = math.pi / 4 + math.pi * k / 2
        x, y = ring * math.cos(a), ring * math.sin(a)
        add_geom(base, f"{name}/rod{k}", "capsule", [rod_r], (0.8, 0.8, 0.82, 1.0),
                 fromto=[x, y, shelf_height, x, y, shelf_height + rod_height])
    return ObjectInfo(name, name, None, True, 0.0, 0.07,
                      points={"slot": (name, (0.0, 0.0, shelf_height)),
                              "top": (name, (0.0, 0.0, shelf_height + rod_height))},
                      axes={"up": (name, UP)})


def add_carton(spec: mujoco.MjSpec, name: str, half: Sequence[float] = (0.12, 0.17, 0.10),
               mass: float = 0.8) -> ObjectInfo:
    """A closed cardboard carton too wide for one hand (0.24 x 0.34 x 0.20 m by default).

    One box collides; the tape is decoration. Points `grip_xpos`, `grip_xneg`,
    `grip_ypos`, `grip_yneg` are the middles of the four side faces; `top` the lid centre.
    """
    hx, hy, hz = half
    body = free_body(spec, name)
    add_geom(body, f"{name}/box", "box", [hx, hy, hz], CARDBOARD, mass, pos=[0, 0, hz])
    tape = (0.85, 0.78, 0.6, 1.0)
    for k, (size, pos) in enumerate((([0.025, hy + 5e-4, 5e-4], [0, 0, 2 * hz]),
                                     ([0.025, 5e-4, 0.04], [0, hy, 2 * hz - 0.04]),
                                     ([0.025, 5e-4, 0.04], [0, -hy, 2 * hz - 0.04]))):
        add_visual(body, f"{name}/tape{k}", "box", size, tape, pos=pos)
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, math.hypot(hx, hy),
                      points={"grip_xpos": (name, (hx, 0.0, hz)),
                              "grip_xneg": (name, (-hx, 0.0, hz)),
                              "grip_ypos": (name, (0.0, hy, hz)),
                              "grip_yneg": (name, (0.0, -hy, hz)),
                              "top": (name, (0.0, 0.0, 2 * hz))},
                      axes={"up": (name, UP)})
