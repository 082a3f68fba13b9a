"""The arena every task shares: floor, table, lights and named camera placeholders.

Physics options are chosen here, explicitly, and children attached later (robots, task
objects) inherit them, so one place decides integrator, timestep and friction cone.
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass

import mujoco
import numpy as np

from dexbench.assets.backgrounds import DEFAULT as BACKDROP_DEFAULT
from dexbench.assets.backgrounds import add_background_library
from dexbench.assets.materials import add_material_library
from dexbench.assets.objects import new_spec
from dexbench.embodiments.builder import TABLE_HALF_SIZE, TABLE_TOP_Z

TABLE_THICKNESS = 0.04
BACKDROP_HALF_SIZE = 3.5  # walls at x, y = +-3.5 m
BACKDROP_HEIGHT = 4.0  # ceiling height


@dataclass(frozen=True)
class PhysicsOptions:
    """Simulator options; the 60 Hz control rate divides the timestep exactly."""

    timestep: float = 1.0 / 240.0
    control_hz: float = 60.0
    integrator: str = "implicitfast"
    cone: str = "elliptic"
    impratio: float = 10.0
    iterations: int = 50
    ls_iterations: int = 20
    arena_mb: float = 4.0  # per-world memory for contacts and constraints

    @property
    def decimation(self) -> int:
        steps = round(1.0 / (self.control_hz * self.timestep))
        if abs(steps * self.timestep * self.control_hz - 1.0) > 1e-9:
            raise ValueError(
                f"timestep {self.timestep} does not divide the control period "
                f"1/{self.control_hz} s: choose a timestep of 1/(k*{self.control_hz:g})"
            )
        return steps


# Cameras as the paper places them: (name, position, point looked at).
CAMERAS = (
    ("front", (-1.5, 0.0, 1.5), (0.0, 0.0, TABLE_TOP_Z)),
    ("left", (0.0, 1.5, 1.5), (0.0, 0.0, TABLE_TOP_Z)),
    ("right", (0.0, -1.5, 1.5), (0.0, 0.0, TABLE_TOP_Z)),
)
CAMERA_FOVY = 47.0


def apply_options(spec: mujoco.MjSpec, options: PhysicsOptions) -> None:
    """Write the physics options into a spec (the arena's or a child's before attach)."""
    spec.option.timestep = options.timestep
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{options.integrator.upper()}")
    spec.option.cone = getattr(mujoco.mjtCone, f"mjCONE_{options.cone.upper()}")
    spec.option.impratio = options.impratio
    spec.option.iterations = options.iterations
    spec.option.ls_iterations = options.ls_iterations
    spec.memory = int(options.arena_mb * 2**20)


def _add_backdrop(world: mujoco.MjsBody) -> None:
    """Four walls and a ceiling around the scene, the background every camera sees.

    Geometry rather than a skybox, because a geom's material can differ per world
    (background variation) and both renderers see it alike; it never collides and lies
    beyond the point-cloud crop.
    """
    half, z, thick = BACKDROP_HALF_SIZE, BACKDROP_HEIGHT / 2, 0.01
    walls = {"north": ([half, 0, z], [thick, half, z]),
             "south": ([-half, 0, z], [thick, half, z]),
             "east": ([0, half, z], [half, thick, z]),
             "west": ([0, -half, z], [half, thick, z]),
             "ceiling": ([0, 0, 2 * z], [half, half, thick])}
    for name, (pos, size) in walls.items():
        world.add_geom(name=f"backdrop/{name}", type=mujoco.mjtGeom.mjGEOM_BOX, pos=pos,
                       size=size, contype=0, conaffinity=0, material=BACKDROP_DEFAULT)


def build_arena(options: PhysicsOptions,
                backgrounds: tuple[pathlib.Path, ...] = ()) -> mujoco.MjSpec:
    """A fresh spec holding floor, table, lights, cameras and the backdrop; `backgrounds`
    are image files the backdrop may show under background variation."""
    spec = new_spec()
    spec.modelname = "dexbench"
    apply_options(spec, options)
    spec.compiler.autolimits = True
    spec.visual.global_.offwidth = 1024
    spec.visual.global_.offheight = 1024
    # A 1024 shadow map keeps soft-rasterized (EGL/OSMesa) frames ~4x faster than the
    # default 4096 with shadows still readable at policy resolutions.
    spec.visual.quality.shadowsize = 1024
    add_background_library(spec, list(backgrounds))
    world = spec.worldbody
    _add_backdrop(world)
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.05],
                   rgba=[0.55, 0.55, 0.55, 1])
    table = world.add_body(name="table", pos=[0, 0, TABLE_TOP_Z - TABLE_THICKNESS / 2])
    table.add_geom(name="table_top", type=mujoco.mjtGeom.mjGEOM_BOX,
                   size=[*TABLE_HALF_SIZE, TABLE_THICKNESS / 2], rgba=[0.62, 0.5, 0.38, 1],
                   friction=[1.0, 0.005, 0.0001])
    leg_h = (TABLE_TOP_Z - TABLE_THICKNESS) / 2
    for i, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1))):
        table.add_geom(name=f"table_leg{i}", type=mujoco.mjtGeom.mjGEOM_BOX,
                       size=[0.03, 0.03, leg_h],
                       pos=[sx * (TABLE_HALF_SIZE[0] - 0.05), sy * (TABLE_HALF_SIZE[1] - 0.05),
                            -TABLE_THICKNESS / 2 - leg_h],
                       rgba=[0.3, 0.25, 0.2, 1])
    world.add_light(name="key", pos=[0, -0.5, 2.5], dir=[0, 0.2, -1], diffuse=[0.7] * 3,
                    castshadow=True)
    world.add_light(name="fill", pos=[-1.5, 1.0, 2.0], dir=[0.6, -0.4, -0.7],
                    diffuse=[0.3] * 3, castshadow=False)
    for name, pos, target in CAMERAS:
        world.add_camera(name=name, pos=list(pos), fovy=CAMERA_FOVY,
                         quat=look_at_quat(pos, target))
    add_material_library(spec)
    return spec


def look_at_quat(pos, target) -> list[float]:
    """Camera orientation looking from `pos` at `target` with world z up.

    MuJoCo cameras look along their -z axis with +y up in the image.
    """
    forward = np.asarray(target, float) - np.asarray(pos, float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.column_stack([right, up, -forward]).ravel())
    return q.tolist()
