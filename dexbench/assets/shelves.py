"""A wall with a board to stand up against it, and a book slot with books.

The wall and the shelf are fixed (mocap) bodies standing on the table; the board and the
books are free. Walls face -x in their own frame (towards a hand coming from -x), shelves
open towards -x.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from dexbench.assets.objects import ObjectInfo, add_geom, free_body, mocap_body

WALL = (0.78, 0.76, 0.72, 1.0)
BOARD = (0.85, 0.75, 0.55, 1.0)


def add_wall(spec: mujoco.MjSpec, name: str, half: Sequence[float] = (0.015, 0.30, 0.175)
             ) -> ObjectInfo:
    """A fixed slab (half extents `half`) standing on the table; its origin is its centre.

    Point `face`: the middle of its -x face at table height. Axis `out`: that face's
    outward normal (-x).
    """
    body = mocap_body(spec, name)
    add_geom(body, f"{name}/geom", "box", half, WALL)
    return ObjectInfo(name, name, None, True, half[2], float((half[0] ** 2 + half[1] ** 2) ** 0.5),
                      points={"face": (name, (-half[0], 0.0, -half[2]))},
                      axes={"out": (name, (-1.0, 0.0, 0.0))})


def add_board(spec: mujoco.MjSpec, name: str, half: Sequence[float] = (0.23, 0.10, 0.02),
              mass: float = 0.5) -> ObjectInfo:
    """A large thin free cuboid lying flat, long along x: a 46 x 20 x 4 cm foam panel of
    0.5 kg (about 135 kg/m^3: a rigid foam board, light enough for one hand to stand up
    by an end). Standing on an end, its centre is 21 cm higher than lying flat.

    Points: `near_edge` and `far_edge`, the middles of its bottom edges at -x and +x.
    Axis `up`: along its length (+x), the axis that is vertical once it stands.
    """
    body = free_body(spec, name)
    add_geom(body, f"{name}/geom", "box", half, BOARD, mass)
    hx, _, hz = half
    return ObjectInfo(name, name, f"{name}/free", False, hz,
                      float((half[0] ** 2 + half[1] ** 2) ** 0.5),
                      points={"near_edge": (name, (-hx, 0.0, -hz)),
                              "far_edge": (name, (hx, 0.0, -hz))},
                      axes={"up": (name, (1.0, 0.0, 0.0))})


SHELF = (0.55, 0.38, 0.22, 1.0)
BOOK = (0.15, 0.35, 0.65, 1.0)
NEIGHBOUR = (0.6, 0.2, 0.2, 1.0)


def add_shelf(spec: mujoco.MjSpec, name: str, inner: Sequence[float] = (0.08, 0.055, 0.06),
              wall: float = 0.01) -> ObjectInfo:
    """A fixed open-topped book slot on the table: a base board, a back and two sides
    round an inner space of half extents `inner` (x depth, y width, z height), open
    towards -x. Its origin is the middle of the base board's top.

    Point `slot`: the middle of the base board's top. Axis `out`: out of the shelf (-x).
    """
    body = mocap_body(spec, name)
    dx, dy, dz = inner
    add_geom(body, f"{name}/base", "box", [dx, dy + wall, wall], SHELF, pos=[0, 0, -wall])
    add_geom(body, f"{name}/back", "box", [wall / 2, dy + wall, dz], SHELF,
             pos=[dx + wall / 2, 0, dz])
    for k, y in enumerate((dy + wall / 2, -(dy + wall / 2))):
        add_geom(body, f"{name}/side{k}", "box", [dx, wall / 2, dz], SHELF, pos=[0, y, dz])
    return ObjectInfo(name, name, None, True, 2 * wall, float(np.hypot(dx + wall, dy + wall)),
                      points={"slot": (name, (0.0, 0.0, 0.0))},
                      axes={"out": (name, (-1.0, 0.0, 0.0))})


def add_book(spec: mujoco.MjSpec, name: str, half: Sequence[float] = (0.075, 0.015, 0.11),
             mass: float = 0.35, rgba: Sequence[float] = BOOK) -> ObjectInfo:
    """A free hardback standing on its bottom edge: `half` is half its depth (x, spine
    at -x), thickness (y) and height (z); 15 x 3 x 22 cm and 0.35 kg by default.

    Point `top`: the middle of its top edge. Axis `up`: its height.
    """
    body = free_body(spec, name)
    add_geom(body, f"{name}/geom", "box", half, rgba, mass)
    return ObjectInfo(name, name, f"{name}/free", False, half[2], float(np.hypot(*half[:2])),
                      points={"top": (name, (0.0, 0.0, half[2]))},
                      axes={"up": (name, (0.0, 0.0, 1.0))})
