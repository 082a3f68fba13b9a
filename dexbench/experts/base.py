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


def phase_machine_state(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                         np.ndarray]:
    """Fresh per-env state of a one-hand phase machine: phase, seconds in it, finger
    closure, and the commanded palm position (n, 3) and frame (n, 3, 3)."""
    return (np.zeros(n, dtype=np.int64), np.zeros(n), np.zeros(n), np.zeros((n, 3)),
            np.repeat(np.eye(3)[None], n, axis=0))
