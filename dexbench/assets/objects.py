"""Procedural objects built in code: nothing is loaded from disk.

Each builder adds one body to a spec and returns its name. Sizes, masses and frictions
are parameters so tasks and physical variation can change them.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco

DEFAULT_FRICTION = (1.0, 0.005, 0.0001)


def add_free_box(
    spec: mujoco.MjSpec,
    name: str,
    half_size: Sequence[float],
    mass: float,
    rgba: Sequence[float] = (0.8, 0.2, 0.2, 1.0),
    friction: Sequence[float] = DEFAULT_FRICTION,
) -> str:
    """A free-floating box whose pose a task sets at reset (joint `<name>/free`)."""
    body = spec.worldbody.add_body(name=name)
    body.add_freejoint(name=f"{name}/free")
    body.add_geom(
        name=f"{name}/geom",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=list(half_size),
        mass=mass,
        rgba=list(rgba),
        friction=list(friction),
        condim=4,
    )
    return name
