"""Observation groups and presets as the paper's appendix defines them.

Groups: policy (previous action), proprio (robot joint positions), contact (per-fingertip
force from the task's contact objects and their moving parts, robot base frame,
clipped to +-20 N), state (task state),
privileged (robot joint velocities, palm/fingertip poses and velocities, task extras;
never in a preset), goal (commanded target). Camera groups (rgb, depth, pointcloud)
are computed by `camera_obs.CameraObservations`.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from dexbench.envs.rotations import quat_apply_inverse
from dexbench.envs.scene import CONTACT_FORCE_CLIP, Scene
from dexbench.envs.task_api import SceneView, Task

STATE_GROUPS = ("policy", "proprio", "contact", "state", "privileged", "goal")
CAMERA_GROUPS = ("rgb", "depth", "pointcloud")


@dataclass(frozen=True)
class ObsPreset:
    groups: tuple[str, ...]
    history: int  # 0: current frame only, no history axis; k: (N, k, ...) stacks
    multiview: bool


PRESETS: dict[str, ObsPreset] = {
    "state": ObsPreset(("policy", "proprio", "contact", "state", "goal"), 0, False),
    "rgb": ObsPreset(("policy", "proprio", "goal", "rgb"), 3, False),
    "rgb_depth": ObsPreset(("policy", "proprio", "goal", "rgb", "depth"), 3, False),
    "pointcloud": ObsPreset(("policy", "proprio", "goal", "pointcloud"), 3, False),
    "3view_rgb": ObsPreset(("policy", "proprio", "goal", "rgb"), 3, True),
    "3view_rgb_depth": ObsPreset(("policy", "proprio", "goal", "rgb", "depth"), 3, True),
    "3view_pointcloud": ObsPreset(("policy", "proprio", "goal", "pointcloud"), 3, True),
}


def resolve_preset(obs: str | tuple[str, ...] | list[str]) -> ObsPreset:
    """The preset called `obs`, or an ad-hoc one for an explicit list of groups."""
    if isinstance(obs, str):
        if obs not in PRESETS:
            raise ValueError(f"unknown observation preset {obs!r}; presets: "
                             f"{', '.join(PRESETS)}, or pass a list of groups")
        return PRESETS[obs]
    unknown = [g for g in obs if g not in (*STATE_GROUPS, *CAMERA_GROUPS)]
    if unknown:
        raise ValueError(f"unknown observation groups {unknown}; groups: "
                         f"{(*STATE_GROUPS, *CAMERA_GROUPS)}")
    return ObsPreset(tuple(obs), 0, False)


class ObservationTerms:
    """Computes each group from the scene view; indices are resolved once."""

    def __init__(self, scene: Scene, view: SceneView, task: Task,
                 fields: dict[str, torch.Tensor]) -> None:
        model, emb = scene.model, scene.embodiment
        self._task, self._view, self._f = task, view, fields
        # Indices on the fields' device (a host index into a GPU tensor blocks the CPU).
        device = fields["qpos"].device
        joints = [model.joint(j) for j in emb.proprio_joints]
        self._qadr = torch.tensor([j.qposadr[0] for j in joints], device=device)
        self._dadr = torch.tensor([j.dofadr[0] for j in joints], device=device)
        self._contact_adr = self._sensor_index(model, scene.contact_sensors, device)
        self._link_adr = self._sensor_index(
            model, [f"{s}:{k}" for s in scene.link_sites
                    for k in ("framepos", "framequat", "framelinvel", "frameangvel")], device)
        per_side = [len(s.fingertip_bodies) for s in emb.sides.values()]
        self._contact_base = torch.tensor(
            [model.body(s.base_body).id for s, n in zip(emb.sides.values(), per_side, strict=True)
             for _ in range(n)], device=device)

    @staticmethod
    def _sensor_index(model, names, device: torch.device) -> torch.Tensor:
        idx = [model.sensor_adr[model.sensor(n).id] + k for n in names
               for k in range(model.sensor_dim[model.sensor(n).id])]
        return torch.tensor(idx, dtype=torch.long, device=device)

    def compute(self, group: str, last_action: torch.Tensor) -> torch.Tensor | None:
        """One group as float32 (N, d), or None where the task has no such term."""
        f, view = self._f, self._view
        if group == "policy":
            out = last_action.clone()
        elif group == "proprio":
            out = f["qpos"][:, self._qadr]
        elif group == "contact":
            if len(self._contact_adr) == 0:
                return None
            # Summed over the task's contact bodies: the force on each fingertip.
            forces = f["sensordata"][:, self._contact_adr].reshape(
                len(last_action), len(self._contact_base), -1, 3).sum(dim=2)
            base_quat = f["xquat"][:, self._contact_base]
            out = quat_apply_inverse(base_quat, forces).clamp(
                -CONTACT_FORCE_CLIP, CONTACT_FORCE_CLIP).flatten(1)
        elif group == "state":
            out = self._task.state_obs(view)
        elif group == "goal":
            out = self._task.goal_obs(view)
        elif group == "privileged":
            parts = [f["qvel"][:, self._dadr], f["sensordata"][:, self._link_adr]]
            extra = self._task.privileged_obs(view)
            out = torch.cat(parts + ([extra] if extra is not None else []), dim=1)
        else:
            raise ValueError(f"unknown observation group {group!r}")
        return None if out is None else out.to(torch.float32)
