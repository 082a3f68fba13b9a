"""Visual and physical variation, sampled per environment at reset from seeded streams.

Every switch is independent. Visual variation changes only rendering-side model fields
(material ids, colours, lights, camera poses and field of view, the backdrop), drawing from the
`train` or `test` appearance pool so that evaluation can use unseen appearances.
Physical variation scales object masses and frictions, articulated-joint damping and
friction and robot actuator gains within ranges; observation noise perturbs proprio and
state. Both are off by default.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import mujoco
import numpy as np
import torch

from dexbench.assets.backgrounds import DEFAULT as BACKDROP_DEFAULT
from dexbench.assets.backgrounds import background_pool, list_images
from dexbench.assets.materials import pool
from dexbench.envs.arena import CAMERAS
from dexbench.envs.scene import Scene
from dexbench.sim.backend import SimBackend

Range = tuple[float, float]


@dataclass(frozen=True)
class VisualVariation:
    enabled: bool = False
    split: str = "train"  # appearance pool: "train" or "test"
    materials: bool = True  # table, floor and object surfaces
    lighting: bool = True  # direction, intensity, colour temperature, number of lights
    exposure: bool = True
    camera_pose: bool = True
    camera_fov: bool = True
    camera_pos_jitter: float = 0.03  # m, per axis
    camera_rot_jitter_deg: float = 3.0
    fov_jitter_deg: float = 4.0
    background: bool = True  # backdrop: procedural gradients/colours (+ user images)
    background_dir: str | None = None  # a folder of .hdr/.png/.jpg images to add

    def background_files(self) -> tuple[pathlib.Path, ...]:
        """The user's background images, when this variation shows them."""
        if not (self.enabled and self.background and self.background_dir):
            return ()
        return tuple(list_images(self.background_dir))


@dataclass(frozen=True)
class PhysicalVariation:
    enabled: bool = False
    object_mass: Range = (0.7, 1.3)  # scale factors
    object_friction: Range = (0.6, 1.4)
    joint_damping: Range = (0.5, 1.5)
    joint_friction: Range = (0.5, 1.5)
    robot_gain: Range = (0.85, 1.15)
    obs_noise: float = 0.0  # std of Gaussian noise on proprio and state


# Light intensity and colour temperature (K) per appearance pool: disjoint ranges.
_INTENSITY = {"train": (0.55, 0.85), "test": (0.85, 1.0)}
_KELVIN = {"train": (3500.0, 5500.0), "test": (5500.0, 8000.0)}


def kelvin_rgb(kelvin: float) -> np.ndarray:
    """A light colour for a colour temperature, warm (3000 K) to cool (8000 K)."""
    t = float(np.clip((kelvin - 3000.0) / 5000.0, 0.0, 1.0))
    return np.array([1.0, 0.82, 0.62]) * (1 - t) + np.array([0.82, 0.9, 1.0]) * t


def _small_rotation(rng: np.random.Generator, max_deg: float) -> np.ndarray:
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    half = math.radians(rng.uniform(-max_deg, max_deg)) / 2
    return np.array([math.cos(half), *(math.sin(half) * axis)])


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


class Variation:
    """Resolves what to vary in a scene once, then writes samples at each reset."""

    def __init__(self, scene: Scene, sim: SimBackend, material_ids: list[int],
                 visual: VisualVariation, physical: PhysicalVariation) -> None:
        self.visual, self.physical = visual, physical
        self._sim = sim
        m = scene.model
        self._base = m
        robot = tuple(f"{s}/" for s in scene.embodiment.sides)
        body_names = [m.body(b).name for b in range(m.nbody)]
        object_bodies = [b for b, n in enumerate(body_names)
                         if b > 0 and n != "table" and not n.startswith(robot)]
        solid = (m.geom_contype != 0) | (m.geom_conaffinity != 0)
        self._object_geoms = [g for g in range(m.ngeom)
                              if m.geom_bodyid[g] in object_bodies and solid[g]]
        self._surface_geoms = [m.geom(n).id for n in ("table_top", "floor")]
        self._object_bodies = [b for b in object_bodies if m.body_mass[b] > 0]
        object_dofs = [m.jnt_dofadr[j] for j in range(m.njnt)
                       if m.jnt_bodyid[j] in object_bodies
                       and m.jnt_type[j] != mujoco.mjtJoint.mjJNT_FREE]
        self._object_dofs = object_dofs
        self._robot_acts = list(range(m.nu))
        self._lights = list(range(m.nlight))
        self._cameras = [m.camera(name).id for name, _, _ in CAMERAS]
        self._backdrop = [g for g in range(m.ngeom) if m.geom(g).name.startswith("backdrop/")]
        library = [m.material(i).name for i in range(m.nmat)]
        library = [n for n in library if n.startswith("bg/") and n != BACKDROP_DEFAULT]
        self._backgrounds = [m.material(n).id for n in background_pool(library, visual.split)]
        self._materials = [material_ids[i] for i in pool(visual.split)]
        self._staged: dict[str, tuple] = {}  # field -> (backend values, host values)

    def apply(self, env_ids: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Sample and write variation for the given environments."""
        if self.visual.enabled:
            self._apply_visual(env_ids, rngs)
        if self.physical.enabled:
            self._apply_physical(env_ids, rngs)
            self._flush(env_ids)
            self._sim.set_const(env_ids)
        self._flush(env_ids)

    def _field(self, name: str) -> np.ndarray:
        """Per-world values of a model field to write: a view of the backend's own
        array on the CPU, a host copy of a GPU one (written back by `_flush`)."""
        if name not in self._staged:
            values = self._sim.model_field(name)
            host = values.numpy() if values.device.type == "cpu" else values.cpu().numpy()
            self._staged[name] = (values, host)
        return self._staged[name][1]

    def _flush(self, env_ids: np.ndarray) -> None:
        """Copy the staged rows of those environments onto the device."""
        for values, host in self._staged.values():
            if values.device.type != "cpu":
                rows = torch.as_tensor(env_ids, device=values.device)
                values[rows] = torch.as_tensor(host[env_ids], device=values.device)
        self._staged = {}

    def _apply_visual(self, env_ids: np.ndarray, rngs: list[np.random.Generator]) -> None:
        v, m = self.visual, self._base
        for env, rng in zip(env_ids, rngs, strict=True):
            if v.materials:
                matid = self._field("geom_matid")
                for g in (*self._surface_geoms, *self._object_geoms):
                    matid[env, g] = rng.choice(self._materials)
                rgba = self._field("geom_rgba")
                rgba[env, self._object_geoms, :3] = 1.0  # the material's texture shows
            if v.background:
                self._field("geom_matid")[env, self._backdrop] = rng.choice(self._backgrounds)
            if v.lighting or v.exposure:
                diffuse = self._field("light_diffuse")
                ldir = self._field("light_dir")
                gain = rng.uniform(0.7, 1.3) if v.exposure else 1.0
                for k, light in enumerate(self._lights):
                    base = m.light_diffuse[light]
                    if v.lighting:
                        on = k == 0 or rng.uniform() < 0.7
                        colour = kelvin_rgb(rng.uniform(*_KELVIN[v.split]))
                        base = on * colour * rng.uniform(*_INTENSITY[v.split])
                        d = m.light_dir[light] + rng.normal(scale=0.25, size=3)
                        ldir[env, light] = d / np.linalg.norm(d)
                    diffuse[env, light] = np.clip(base * gain, 0.0, 1.0)
            if v.camera_pose:
                pos, quat = self._field("cam_pos"), self._field("cam_quat")
                for cam in self._cameras:
                    pos[env, cam] = m.cam_pos[cam] + rng.uniform(
                        -v.camera_pos_jitter, v.camera_pos_jitter, size=3)
                    quat[env, cam] = _quat_mul(m.cam_quat[cam], _small_rotation(
                        rng, v.camera_rot_jitter_deg))
            if v.camera_fov:
                fovy = self._field("cam_fovy")
                for cam in self._cameras:
                    fovy[env, cam] = m.cam_fovy[cam] + rng.uniform(-v.fov_jitter_deg,
                                                                   v.fov_jitter_deg)

    def _apply_physical(self, env_ids: np.ndarray, rngs: list[np.random.Generator]) -> None:
        p, m = self.physical, self._base
        mass, inertia = self._field("body_mass"), self._field("body_inertia")
        friction = self._field("geom_friction")
        damping, frictionloss = self._field("dof_damping"), self._field("dof_frictionloss")
        gain, bias = self._field("actuator_gainprm"), self._field("actuator_biasprm")
        for env, rng in zip(env_ids, rngs, strict=True):
            for b in self._object_bodies:
                s = rng.uniform(*p.object_mass)
                mass[env, b], inertia[env, b] = m.body_mass[b] * s, m.body_inertia[b] * s
            for g in self._object_geoms:
                friction[env, g, 0] = m.geom_friction[g, 0] * rng.uniform(*p.object_friction)
            for d in self._object_dofs:
                damping[env, d] = m.dof_damping[d] * rng.uniform(*p.joint_damping)
                frictionloss[env, d] = m.dof_frictionloss[d] * rng.uniform(*p.joint_friction)
            for a in self._robot_acts:
                s = rng.uniform(*p.robot_gain)
                gain[env, a, 0] = m.actuator_gainprm[a, 0] * s
                bias[env, a, 1] = m.actuator_biasprm[a, 1] * s
