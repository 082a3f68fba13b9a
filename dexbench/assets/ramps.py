"""A 15 deg ramp with a plateau, and the post pairs that obstruct it.

The ramp (fixed) rises along +x in its own frame: a solid wedge, a flat plateau with a
stop at its far end, and low side rails that keep a ball on it. Obstacle pairs are
separate fixed bodies a task stands at some of the ramp's `slot<i>` points; their posts
reach into the wedge (fixed bodies do not collide with each other).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from dexbench.assets.meshes import add_mesh
from dexbench.assets.objects import UP, ObjectInfo, add_geom, mocap_body

RAMP = (0.62, 0.66, 0.7, 1.0)
RAIL = (0.35, 0.37, 0.4, 1.0)
POST = (0.85, 0.45, 0.15, 1.0)
SLOTS = (0.2, 0.35, 0.5, 0.65, 0.8)  # obstacle slots, as fractions of the slope length


def add_ramp(spec: mujoco.MjSpec, name: str, slope: float = math.radians(15.0),
             length: float = 0.30, plateau: float = 0.10, half_width: float = 0.15,
             rail: float = 0.02) -> ObjectInfo:
    """A ramp `length` m along its incline, then a `plateau` m long flat top.

    The origin is the middle of its footprint on the table; the foot edge is at
    -x. Points: `foot` (centre of the foot edge), `target` (centre of the crest, where
    the incline meets the plateau: a ball is over it when its centre is past the crest
    and at least as high), `slot0`..`slot4` (centre line of the incline at `SLOTS`).
    Axes: `uphill` (horizontal, up the incline), `up`.
    """
    base = mocap_body(spec, name)
    run, rise = length * math.cos(slope), length * math.sin(slope)
    stop = 0.02
    x0 = -(run + plateau + stop) / 2
    w = half_width
    verts = np.array([[x0 + x, y, z] for y in (-w, w)
                      for x, z in ((0.0, 0.0), (run, 0.0), (run, rise))])
    faces = np.array([[0, 1, 2], [3, 5, 4], [0, 3, 4], [0, 4, 1], [1, 4, 5], [1, 5, 2],
                      [0, 2, 5], [0, 5, 3]], dtype=np.int32)
    add_geom(base, f"{name}/incline", "mesh", [0.0], RAMP,
             meshname=add_mesh(spec, f"{name}/incline", verts, faces))
    top_x = x0 + run
    add_geom(base, f"{name}/plateau", "box", [plateau / 2, w, rise / 2], RAMP,
             pos=[top_x + plateau / 2, 0, rise / 2])
    add_geom(base, f"{name}/stop", "box", [stop / 2, w, (rise + rail) / 2], RAIL,
             pos=[top_x + plateau + stop / 2, 0, (rise + rail) / 2])
    tilt = [math.cos(slope / 2), 0.0, -math.sin(slope / 2), 0.0]
    normal = np.array([-math.sin(slope), 0.0, math.cos(slope)])
    for k, y in enumerate((w - 0.005, -(w - 0.005))):
        mid = np.array([x0 + run / 2, y, rise / 2]) + normal * rail / 2
        add_geom(base, f"{name}/rail{k}", "box", [length / 2, 0.005, rail / 2], RAIL,
                 pos=mid.tolist(), quat=tilt)
        add_geom(base, f"{name}/top_rail{k}", "box", [plateau / 2, 0.005, rail / 2], RAIL,
                 pos=[top_x + plateau / 2, y, rise + rail / 2])
    slots = {f"slot{i}": (name, (x0 + s * run, 0.0, s * rise)) for i, s in enumerate(SLOTS)}
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(-x0, w),
                      points={"foot": (name, (x0, 0.0, 0.0)),
                              "target": (name, (top_x, 0.0, rise)), **slots},
                      axes={"uphill": (name, (1.0, 0.0, 0.0)), "up": (name, UP)})


def add_obstacle_pair(spec: mujoco.MjSpec, name: str, gap: float = 0.076,
                      radius: float = 0.012, height: float = 0.04) -> ObjectInfo:
    """Two posts (fixed) `gap` apart along y, standing `height` above the body origin.

    Stood at a ramp slot, the posts also reach 3 cm below it, into the wedge, so none
    of the incline shows under them. Point `centre` is the middle of the gap.
    """
    base = mocap_body(spec, name)
    below = 0.03
    for k, y in enumerate((gap / 2 + radius, -(gap / 2 + radius))):
        add_geom(base, f"{name}/post{k}", "cylinder", [radius, (height + below) / 2], POST,
                 pos=[0, y, (height - below) / 2])
    return ObjectInfo(name, name, None, True, 0.0, gap / 2 + 2 * radius,
                      points={"centre": (name, (0.0, 0.0, 0.0))})
