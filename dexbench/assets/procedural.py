"""Vessel presets on top of `meshes.add_lathe_object`: mug, cup, jar (open) and bottle.

Each stands upright with its bottom at the body origin, so `rest_height` is 0; `up` is
the vessel axis. Open vessels mark their rim (a disc over the opening) as a do-not-touch
zone, since the pouring tasks forbid fingers on or over the rim.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco

from dexbench.assets.meshes import add_lathe_object, radius_at
from dexbench.assets.objects import ObjectInfo, Vec3, Zone, add_geom
from dexbench.assets.vessels import ring_zone

UP = (0.0, 0.0, 1.0)


def _open_info(name: str, radius: float, height: float, reach: float,
               extra_points: dict[str, tuple[str, Vec3]] | None = None,
               zone: Zone | None = None) -> ObjectInfo:
    """`zone` defaults to the rim volume on the root body (contacts there, on the wall)."""
    rim = (0.0, 0.0, height)
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, reach,
                      points={"rim": (name, rim), "bottom": (name, (0.0, 0.0, 0.0)),
                              **(extra_points or {})},
                      axes={"up": (name, UP)},
                      zones=(zone or Zone(name, "cylinder", rim, radius + 0.005, 0.01),))


def add_cup(spec: mujoco.MjSpec, name: str, radius: float = 0.035, height: float = 0.10,
            wall: float = 0.004, mass: float = 0.12, band: float = 0.01,
            rgba: Sequence[float] = (0.3, 0.6, 0.85, 1.0)) -> ObjectInfo:
    """A handle-less cup, slightly narrower at the foot; `radius` is at the rim.

    The wall's top `band` (m) is the no-touch rim: its own pieces in the zone body
    `<name>/rim` (their share of the mass by height), the rest of the cup in the root.
    """
    profile = [(0.8 * radius, 0.0), (radius, height)]
    below = height - band
    r_below = radius_at(profile, below)
    body = add_lathe_object(spec, name, [profile[0], (r_below, below)], wall,
                            mass * below / height, rgba, bottom_thickness=0.006)
    radii = ((r_below - wall, r_below), (radius - wall, radius))
    ring_zone(spec, body, f"{name}/rim", below, radii, band, mass * band / height, rgba)
    zone = Zone(f"{name}/rim", "cylinder", (0.0, 0.0, band / 2), radius + 0.005,
                band / 2 + 0.003)
    return _open_info(name, radius, height, radius, zone=zone)


def add_mug(spec: mujoco.MjSpec, name: str, radius: float = 0.04, height: float = 0.095,
            wall: float = 0.006, mass: float = 0.25,
            rgba: Sequence[float] = (0.85, 0.85, 0.9, 1.0)) -> ObjectInfo:
    """A straight mug with a capsule handle on its +x side (15% of the mass).

    Points: `rim` (centre of the opening), `bottom`, `handle` (middle of the grip bar).
    """
    body = add_lathe_object(spec, name, [(0.95 * radius, 0.0), (radius, 0.008),
                                         (radius, height)],
                            wall, 0.85 * mass, rgba, bottom_thickness=0.008)
    grip_x, bar = radius + 0.028, 0.006  # leaves a 2.2 cm gap for fingers
    arm = (0.7071068, 0, 0.7071068, 0)  # capsule along x
    parts = (((grip_x, 0, 0.5 * height), (1, 0, 0, 0), 0.2 * height),
             ((radius + 0.014, 0, 0.75 * height), arm, 0.014),
             ((radius + 0.014, 0, 0.25 * height), arm, 0.014))
    for k, (pos, quat, half_len) in enumerate(parts):
        add_geom(body, f"{name}/handle{k}", "capsule", [bar, half_len], rgba, 0.05 * mass,
                 pos=list(pos), quat=list(quat))
    return _open_info(name, radius, height, grip_x + bar,
                      {"handle": (name, (grip_x, 0.0, 0.5 * height))})


def add_jar(spec: mujoco.MjSpec, name: str, radius: float = 0.045, height: float = 0.12,
            wall: float = 0.005, mass: float = 0.3,
            rgba: Sequence[float] = (0.75, 0.5, 0.3, 1.0)) -> ObjectInfo:
    """An open, lidless jar with a shoulder and a wide neck (80% of the body radius).

    Every bend of the wall needs its own ring of convex pieces, so it uses 12 sectors.
    """
    neck = 0.8 * radius
    profile = [(0.9 * radius, 0.0), (radius, 0.01), (radius, 0.78 * height),
               (neck, 0.88 * height), (neck, height)]
    add_lathe_object(spec, name, profile, wall, mass, rgba, bottom_thickness=0.01,
                     sectors=12)
    return _open_info(name, neck, height, radius)


def add_bottle(spec: mujoco.MjSpec, name: str, radius: float = 0.03, height: float = 0.18,
               mass: float = 0.2, rgba: Sequence[float] = (0.2, 0.55, 0.35, 1.0)
               ) -> ObjectInfo:
    """A closed bottle: body, shoulder and a neck of radius 0.012 m.

    Points: `centre` (mid-height), `top` (centre of the cap face).
    """
    neck = 0.012
    profile = [(radius * 0.92, 0.0), (radius, 0.008), (radius, 0.62 * height),
               (neck, 0.85 * height), (neck, height)]
    add_lathe_object(spec, name, profile, None, mass, rgba)
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, radius,
                      points={"centre": (name, (0.0, 0.0, height / 2)),
                              "top": (name, (0.0, 0.0, height))},
                      axes={"up": (name, UP)})
