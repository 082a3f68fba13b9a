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
INTEGRATION = int(mujoco.mjtState.mjSTATE_INTEGRATION)  # every component: a world's full row


def state_layout(model: mujoco.MjModel, spec: int) -> dict[str, slice]:
    """Where each mjtState component of `spec` lies in a state vector of that spec.

    Components are concatenated in bit order (as `mj_getState` does); the key is the
    component's name without its prefix (`qpos`, `warmstart`, ...).
    """
    layout, offset = {}, 0
    for bit in range(INTEGRATION.bit_length()):
        if spec & (1 << bit):
            size = mujoco.mj_stateSize(model, 1 << bit)
            name = mujoco.mjtState(1 << bit).name.removeprefix("mjSTATE_").lower()
            layout[name] = slice(offset, offset + size)
            offset += size
    return layout


def state_columns(model: mujoco.MjModel, spec: int) -> torch.Tensor:
    """Indices of a `spec` state's entries within the full (`INTEGRATION`) state row."""
    full = state_layout(model, INTEGRATION)
    return torch.cat([torch.arange(full[name].start, full[name].stop)
                      for name in state_layout(model, spec)])


def lookup_field(fields: dict[str, torch.Tensor], name: str) -> torch.Tensor:
    """A backend's field by name, or an error listing the fields it has."""
    try:
        return fields[name]
    except KeyError:
        raise KeyError(f"unknown field {name!r}; have {sorted(fields)}") from None


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

    def step(self, nsubsteps: int, acceleration: bool = False) -> None:
        """Advance every world by `nsubsteps` physics steps with the current ctrl.

        Derived fields are then current at the new state up to velocities; with
        `acceleration`, also acceleration-stage ones (contact-force sensors), so that they
        describe the new state rather than the last substep.
        """

    def reset(self, env_ids: torch.Tensor) -> None:
        """Reset those worlds to the model defaults (qpos0, zero velocity, time 0)."""

    def forward(self, env_ids: torch.Tensor, acceleration: bool = False) -> None:
        """Recompute derived fields of those worlds after their state was written."""

    def get_state(self, spec: int = INTEGRATION) -> torch.Tensor:
        """State of every world, (num_envs, mj_stateSize(spec)); default: all of it."""

    def set_state(self, env_ids: torch.Tensor, state: torch.Tensor, spec: int = INTEGRATION,
                  acceleration: bool = False) -> None:
        """Overwrite the `spec` components of those worlds' state, then `forward` them."""
