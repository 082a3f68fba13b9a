"""The batched simulator interface every backend implements.

Fields are exposed as live torch tensors shaped (num_envs, ...): state fields
(`STATE_FIELDS`) are writable views of the simulator state; derived fields
(`DERIVED_FIELDS`) are current after `step` and `forward`. Upper layers never see the
backend's own arrays, so observation terms, rewards and success predicates run
unchanged on CPU (numpy-backed) and GPU tensors.
"""

from __future__ import annotations

from typing import Protocol

import mujoco
import torch

STATE_FIELDS = ("qpos", "qvel", "ctrl", "mocap_pos", "mocap_quat", "userdata")
DERIVED_FIELDS = ("xpos", "xquat", "geom_xpos", "site_xpos", "site_xmat", "sensordata")


class SimBackend(Protocol):
    """N worlds of one compiled model."""

    model: mujoco.MjModel
    num_envs: int
    device: torch.device

    def field(self, name: str) -> torch.Tensor:
        """A live (num_envs, ...) view of a state or derived field."""

    def model_field(self, name: str) -> torch.Tensor:
        """Writable per-world values (num_envs, ...) of a model field (variation)."""

    def set_const(self, env_ids) -> None:
        """Recompute derived model constants of those worlds after editing fields."""

    def warning_counts(self) -> torch.Tensor:
        """(num_envs,) simulator warnings per world since its last reset; never silent."""

    def step(self, nsubsteps: int) -> None:
        """Advance every world by `nsubsteps` physics steps with the current ctrl."""

    def reset(self, env_ids: torch.Tensor) -> None:
        """Reset those worlds to the model defaults (qpos0, zero velocity, time 0)."""

    def forward(self, env_ids: torch.Tensor) -> None:
        """Recompute derived fields of those worlds after their state was written."""

    def get_state(self) -> torch.Tensor:
        """Full physics state (mjSTATE_INTEGRATION) of every world, (num_envs, nstate)."""

    def set_state(self, env_ids: torch.Tensor, state: torch.Tensor) -> None:
        """Overwrite the full physics state of those worlds, then `forward` them."""
