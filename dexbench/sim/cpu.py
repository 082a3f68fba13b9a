"""CPU backend: `mujoco.batch.Batch`, one thread pool stepping N worlds.

Results are bit-identical at any thread count (a property of `mujoco.batch`), so the
same seed gives the same episode on a laptop and on a 64-core node. The batch is
persistent (one MjData per world): observations need positions and velocities that are
current after a step, and a persistent batch computes them once and reuses them in the
next step instead of recomputing. Memory is about num_envs x the model's arena size.
"""

from __future__ import annotations

import os
import warnings

import mujoco
import mujoco.batch
import numpy as np
import torch

from dexbench.sim.backend import (
    DERIVED_FIELDS,
    INTEGRATION,
    STATE_FIELDS,
    lookup_field,
    state_columns,
)

_VEL = mujoco.mjtStage.mjSTAGE_VEL.value
_ACC = mujoco.mjtStage.mjSTAGE_ACC.value


class CpuBackend:
    """N MjData-equivalent worlds of one model, stepped on `nthread` threads (0: all)."""

    def __init__(self, model: mujoco.MjModel, num_envs: int, nthread: int = 0) -> None:
        self.model = model
        self.num_envs = num_envs
        self.device = torch.device("cpu")
        threads = nthread or os.cpu_count() or 1
        self.batch = mujoco.batch.Batch(model, num_envs, nthread=min(threads, num_envs),
                                        persistent=True)
        self._fields: dict[str, torch.Tensor] = {}
        for name in (*STATE_FIELDS, *DERIVED_FIELDS):
            self._fields[name] = self._as_tensor(self.batch.bind(name))
        self._state = self._as_tensor(self.batch.state)
        self._spec_columns: dict[int, torch.Tensor] = {}
        self.per_world_model = False  # set once any model field gets per-world values

    @staticmethod
    def _as_tensor(array: np.ndarray) -> torch.Tensor:
        # Derived fields are read-only numpy views; torch shares them without copying
        # and upper layers never write them.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            return torch.from_numpy(array)

    @property
    def nthread(self) -> int:
        return self.batch.nthread

    def field(self, name: str) -> torch.Tensor:
        return lookup_field(self._fields, name)

    def model_field(self, name: str) -> torch.Tensor:
        """A writable (num_envs, ...) view of per-world values of a model field."""
        self.per_world_model = True
        return torch.from_numpy(self.batch.expand(name))

    def set_const(self, env_ids) -> None:
        """Recompute model constants (e.g. subtree masses) after per-world edits."""
        self.batch.set_const(ids=np.asarray(env_ids))

    def world_model(self, env: int, out: mujoco.MjModel) -> mujoco.MjModel:
        """World `env`'s model (shared assets, its own per-world fields), into `out`."""
        return self.batch.get_model(env, out) if self.per_world_model else self.model

    def warning_counts(self) -> torch.Tensor:
        """(num_envs,) MuJoCo warnings (contact/constraint overflow, instability) so far."""
        return torch.from_numpy(self.batch.warning[:, :, 0].sum(axis=1))

    def step(self, nsubsteps: int, acceleration: bool = False) -> None:
        self.batch.step(nstep=nsubsteps, stage=_ACC if acceleration else _VEL)

    def reset(self, env_ids: torch.Tensor) -> None:
        self.batch.reset(ids=env_ids.numpy(), stage=mujoco.mjtStage.mjSTAGE_NONE.value)

    def forward(self, env_ids: torch.Tensor, acceleration: bool = False) -> None:
        self.batch.forward(ids=env_ids.numpy(), stage=_ACC if acceleration else _VEL)

    def _columns(self, spec: int) -> torch.Tensor:
        if spec not in self._spec_columns:
            self._spec_columns[spec] = state_columns(self.model, spec)
        return self._spec_columns[spec]

    def get_state(self, spec: int = INTEGRATION) -> torch.Tensor:
        if spec == INTEGRATION:
            return self._state.clone()
        return self._state[:, self._columns(spec)]  # advanced indexing copies

    def set_state(self, env_ids: torch.Tensor, state: torch.Tensor, spec: int = INTEGRATION,
                  acceleration: bool = False) -> None:
        rows = torch.as_tensor(env_ids, dtype=torch.long).reshape(-1)
        self._state[rows[:, None], self._columns(spec)] = state.to(self._state.dtype)
        self.forward(rows, acceleration)
