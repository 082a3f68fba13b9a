"""What the environment needs from a task, and the read-only view a task gets back.

A task is (objects, reset distribution, observation terms, success predicate, dense
reward, horizon). It builds objects through `dexbench.assets` and reads state only
through `SceneView`, whose accessors return torch tensors on the backend's device, so
the same predicate runs on the CPU and the GPU backends.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Hashable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets.objects import Zone
from dexbench.embodiments.builder import DEFAULT_WORKSPACE
from dexbench.envs.rotations import quat_apply

ZONE_CONTACTS = 16  # contacts a no-touch sensor reports per hand (the deepest first)


def zone_key(zone: Zone) -> str:
    """The name prefix of a no-touch zone's contact sensors (one per hand)."""
    return f"touch:{zone.body}:{zone.kind}:{zone.pos}:{zone.radius}:{zone.half_length}"


def touch_key(a: str, b: str) -> str:
    """The name of the contact sensor of whether bodies `a`'s and `b`'s subtrees touch."""
    return f"touching:{a}:{b}"


def link_force_key(link: str, obj: str) -> str:
    """The name of the contact sensor of the net force body `obj`'s subtree exerts on the
    hand link (body) `link`."""
    return f"{link}:link_force:{obj}"


@dataclass
class ResetSample:
    """Initial object state for n environments, drawn by a task.

    `free_poses` maps a free joint name to (n, 7) poses (position, quaternion wxyz);
    `mocap_poses` maps a mocap body (fixed objects) to (n, 7) poses; `joint_pos` maps a
    hinge/slide joint name to (n,) values; `goal` is (n, d) or None.
    """

    free_poses: dict[str, np.ndarray] = field(default_factory=dict)
    mocap_poses: dict[str, np.ndarray] = field(default_factory=dict)
    joint_pos: dict[str, np.ndarray] = field(default_factory=dict)
    goal: np.ndarray | None = None


class SceneView:
    """Named, batched read access to simulator state for tasks and observation terms."""

    def __init__(self, model: mujoco.MjModel, fields: dict[str, torch.Tensor],
                 fingertip_sites: list[str], palm_sites: list[str],
                 hand_geoms: list[int], control_dt: float,
                 link_force_sensors: Mapping[tuple[str, str], Sequence[str]] | None = None,
                 ) -> None:
        self._model = model
        self._link_force_sensors = link_force_sensors or {}
        self.control_dt = control_dt  # s per control step: tasks that time events count steps
        self._f = fields
        device = fields["xpos"].device
        self.hand_geom_ids = torch.tensor(hand_geoms, dtype=torch.long, device=device)
        # A hand geom's thickness: its smallest bounding-box half-extent.
        self.hand_geom_thickness = torch.as_tensor(
            model.geom_aabb[hand_geoms, 3:].min(axis=1), device=device)
        self._ids: dict[tuple[str, str], int] = {}  # name lookups are slow; cache them
        # Index tensors and constants live on the fields' device: a host index into a GPU
        # tensor is a blocking copy that stalls the CPU until the queued physics is done
        # (constants: `constant`).
        self.fingertip_ids = torch.tensor([model.site(s).id for s in fingertip_sites],
                                          device=device)
        self.palm_ids = torch.tensor([model.site(s).id for s in palm_sites], device=device)
        self._constants: dict[Hashable, torch.Tensor] = {}
        self.initial_body_pos: dict[str, torch.Tensor] = {}
        self.goal: torch.Tensor | None = None

    def body_id(self, name: str) -> int:
        key = ("body", name)
        if key not in self._ids:
            self._ids[key] = self._model.body(name).id
        return self._ids[key]

    def _qpos_adr(self, joint: str) -> int:
        key = ("qpos", joint)
        if key not in self._ids:
            self._ids[key] = int(self._model.joint(joint).qposadr[0])
        return self._ids[key]

    def _dof_adr(self, joint: str) -> int:
        key = ("dof", joint)
        if key not in self._ids:
            self._ids[key] = int(self._model.joint(joint).dofadr[0])
        return self._ids[key]

    def body_pos(self, name: str) -> torch.Tensor:
        """(N, 3) world position of a body's frame."""
        return self._f["xpos"][:, self.body_id(name)]

    def body_quat(self, name: str) -> torch.Tensor:
        """(N, 4) world orientation (w, x, y, z) of a body's frame."""
        return self._f["xquat"][:, self.body_id(name)]

    def joint_pos(self, name: str) -> torch.Tensor:
        """(N,) position of a hinge or slide joint."""
        return self._f["qpos"][:, self._qpos_adr(name)]

    def free_joint_vel(self, name: str) -> torch.Tensor:
        """(N, 6) linear and angular velocity of a free joint."""
        adr = self._dof_adr(name)
        return self._f["qvel"][:, adr : adr + 6]

    @property
    def memory(self) -> torch.Tensor:
        """(N, memory_size) task memory kept in the simulator state (zero at reset).

        It lives in MuJoCo's `userdata`, part of the full physics state, so restoring a
        recorded state restores e.g. the stages a long-horizon task has completed.
        """
        return self._f["userdata"]

    def constant(self, key: Hashable, values) -> torch.Tensor:
        """`values` (a tensor keeps its dtype; numbers get the fields' dtype) as a tensor
        on the fields' device, made on the first call with `key`: a task's fixed
        geometry, copied to the GPU once rather than every step."""
        if key not in self._constants:
            xpos = self._f["xpos"]
            dtype = values.dtype if isinstance(values, torch.Tensor) else xpos.dtype
            self._constants[key] = torch.as_tensor(values, dtype=dtype, device=xpos.device)
        return self._constants[key]

    def _vector(self, local: tuple[float, float, float]) -> torch.Tensor:
        return self.constant(("body-frame", *map(float, local)), local)

    def point_pos(self, body: str, local: tuple[float, float, float]) -> torch.Tensor:
        """(N, 3) world position of a point fixed in a body's frame."""
        pos = self.body_pos(body)
        return pos + quat_apply(self.body_quat(body), self._vector(local).expand(pos.shape))

    def axis(self, body: str, local: tuple[float, float, float]) -> torch.Tensor:
        """(N, 3) world direction of an axis fixed in a body's frame."""
        vec = self._vector(local).expand(self.body_pos(body).shape)
        return quat_apply(self.body_quat(body), vec)

    def zone_contacts(self, zone: Zone) -> tuple[torch.Tensor, torch.Tensor]:
        """Contacts between any hand and `zone.body`: (N, K) whether each slot holds one
        and (N, K, 3) its world position (the scene adds the sensors for task zones)."""
        key = ("zone", zone_key(zone))
        if key not in self._ids:
            model = self._model
            names = [model.sensor(i).name for i in range(model.nsensor)]
            self._ids[key] = [int(model.sensor_adr[i]) for i, n in enumerate(names)
                              if n.startswith(zone_key(zone) + ":")]
            if not self._ids[key]:
                raise KeyError(f"no contact sensors for zone {zone}; is it a task zone?")
        data = torch.cat([self._f["sensordata"][:, a : a + 4 * ZONE_CONTACTS]
                          for a in self._ids[key]], dim=1).unflatten(1, (-1, 4))
        return data[..., 0] > 0, data[..., 1:]

    def link_forces(self, obj: str, side: str) -> torch.Tensor:
        """(N, L, 3) net contact force, world frame, that body `obj` and the bodies below
        it exert on each link of hand `side` (its bodies with geoms, in model order): a
        grip is judged link by link (the scene adds the sensors for the task's
        `link_force_bodies`)."""
        key = ("link_force", obj, side)
        if key not in self._constants:
            names = self._link_force_sensors.get((obj, side))
            if not names:
                raise KeyError(f"no link force sensors for {obj!r} on the {side} hand; is it "
                               "one of the task's link_force_bodies?")
            adr = [int(self._model.sensor(n).adr[0]) for n in names]
            self.constant(key, torch.tensor([a + k for a in adr for k in range(3)]))
        return self._f["sensordata"][:, self._constants[key]].unflatten(1, (-1, 3))

    def touching(self, a: str, b: str) -> torch.Tensor:
        """(N,) whether the subtrees of bodies `a` and `b` are in contact (the scene adds
        a sensor for each of the task's `touch_pairs`)."""
        key = ("touching", touch_key(a, b))
        if key not in self._ids:
            try:
                self._ids[key] = int(self._model.sensor(touch_key(a, b)).adr[0])
            except KeyError:
                raise KeyError(f"no contact sensor for {a!r} and {b!r}; is the pair one of "
                               "the task's touch_pairs?") from None
        return self._f["sensordata"][:, self._ids[key]] > 0

    def hand_geom_pos(self) -> torch.Tensor:
        """(N, G, 3) centres of every collision geom of every hand."""
        return self._f["geom_xpos"][:, self.hand_geom_ids]

    def fingertip_pos(self) -> torch.Tensor:
        """(N, F, 3) fingertip points of every hand, right hand first."""
        return self._f["site_xpos"][:, self.fingertip_ids]

    def palm_pos(self) -> torch.Tensor:
        """(N, H, 3) hand-frame origins, right hand first."""
        return self._f["site_xpos"][:, self.palm_ids]


class Task(ABC):
    """A benchmark task. Subclasses are mostly data plus small predicate functions."""

    name: ClassVar[str]
    category: ClassVar[str]
    instruction: ClassVar[str]  # language instruction for VLAs and datasets
    description: ClassVar[str] = ""  # the paper's task description
    success_text: ClassVar[str] = ""  # the paper's success condition, in words
    episode_seconds: ClassVar[float] = 20.0
    bimanual: ClassVar[bool] = False  # True: needs two hands
    default_embodiment: ClassVar[str] = "floating_shadow"
    contact_bodies: ClassVar[tuple[str, ...]] = ()  # fingertip contact forces: from these
    # bodies' subtrees (the `contact` group), summed per fingertip
    zones: ClassVar[tuple[Zone, ...]] = ()  # no-touch zones: the scene senses hand contacts
    link_force_bodies: ClassVar[tuple[str, ...]] = ()  # the scene senses the contact force
    # these bodies' subtrees exert on every hand link (`SceneView.link_forces`)
    touch_pairs: ClassVar[tuple[tuple[str, str], ...]] = ()  # the scene senses whether
    # these bodies' subtrees touch (`SceneView.touching`)
    expert: ClassVar[object | None] = None  # the scripted expert's plan (`tasks.plans`)
    deviations: ClassVar[tuple[str, ...]] = ()  # where success differs from the paper's
    tracked_bodies: ClassVar[tuple[str, ...]] = ()  # bodies whose reset pose is kept
    memory_size: ClassVar[int] = 0  # floats of per-env memory (`SceneView.memory`)
    # Where the hands work (world x, y; height above the table top): arm mounts are
    # placed relative to it (`builder._palm_home`), the floating wrist is not.
    workspace: ClassVar[tuple[float, float, float]] = DEFAULT_WORKSPACE

    @classmethod
    def success_doc(cls) -> str:
        """The paper's success condition, then every deviation from it (the task's own
        and its templates'), for the docs."""
        notes = dict.fromkeys(n for c in reversed(cls.__mro__)
                              for n in c.__dict__.get("deviations", ()))
        return " ".join([cls.success_text, *notes])

    @abstractmethod
    def build(self, spec: mujoco.MjSpec) -> None:
        """Add the task's objects (through `dexbench.assets`) to the scene spec."""

    @abstractmethod
    def sample_reset(self, rngs: list[np.random.Generator]) -> ResetSample:
        """Draw initial object states, one generator per environment being reset."""

    def update(self, view: SceneView) -> None:  # noqa: B027  (optional hook)
        """Advance task memory after each control step (stage latches); no-op by default."""

    @abstractmethod
    def success(self, view: SceneView) -> torch.Tensor:
        """(N,) bool: the paper's success condition holds now."""

    @abstractmethod
    def reward(self, view: SceneView) -> torch.Tensor:
        """(N,) float dense reward for RL."""

    def state_obs(self, view: SceneView) -> torch.Tensor | None:
        """(N, d) observable task state, or None."""
        return None

    def goal_obs(self, view: SceneView) -> torch.Tensor | None:
        """(N, d) commanded target, or None for tasks without a goal."""
        return None

    def privileged_obs(self, view: SceneView) -> torch.Tensor | None:
        """(N, d) task quantities withheld from policies (object velocities, ...)."""
        return None
