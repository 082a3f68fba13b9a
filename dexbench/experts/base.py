"""The interface every scripted expert implements, so collection never knows the task."""

from __future__ import annotations

from typing import Protocol

import numpy as np
import torch


class Expert(Protocol):
    """A closed-loop script over one batched `DexEnv`'s privileged state.

    `reset(env_ids)` is called after the environment reset those envs; `act()` returns
    absolute joint targets for every env, shape (num_envs, action_dim), in the env's
    action layout.
    """

    def reset(self, env_ids: torch.Tensor) -> None: ...

    def act(self) -> torch.Tensor: ...


def host_ids(env_ids: torch.Tensor | np.ndarray | list[int]) -> np.ndarray:
    """Env indices as a numpy array: experts keep their per-env state on the host."""
    return np.asarray(env_ids.cpu() if isinstance(env_ids, torch.Tensor) else env_ids)
