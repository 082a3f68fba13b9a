"""Observation history and action chunking with re-planning, per env of a batch.

A chunk policy predicts `horizon` actions from the last `n_obs_steps` frames, executes
the first `n_action_steps` and then plans again. Envs reset at different times, so each
env has its own history and queue; one call plans for exactly the envs whose queue ran
out, as one batch.
"""

from __future__ import annotations

from collections.abc import Callable

import torch

Planner = Callable[[dict[str, torch.Tensor]], torch.Tensor]


class ObsWindow:
    """The last `n_obs_steps` frames of each env, (N, To, ...) per key; the first frame
    after a reset fills the whole window."""

    def __init__(self, num_envs: int, n_obs_steps: int,
                 device: torch.device | str = "cpu") -> None:
        self.n_obs_steps, self.device = n_obs_steps, torch.device(device)
        self.history: dict[str, torch.Tensor] = {}
        self.fresh = torch.ones(num_envs, dtype=torch.bool, device=self.device)

    def reset(self, env_ids: torch.Tensor | slice = slice(None)) -> None:
        self.fresh[env_ids] = True

    def push(self, obs: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """Add one frame per env (N, ...) per key; the windows."""
        for key, value in obs.items():
            value = value.to(self.device)
            stack = self.history.get(key)
            if stack is None:
                stack = value[:, None].repeat(1, self.n_obs_steps, *[1] * (value.dim() - 1))
            else:
                stack = torch.cat([stack[:, 1:], value[:, None]], dim=1)
                stack[self.fresh] = value[self.fresh, None]
            self.history[key] = stack
        self.fresh[:] = False
        return self.history


class ChunkedActor:
    def __init__(self, num_envs: int, n_obs_steps: int, n_action_steps: int,
                 action_dim: int, device: torch.device | str = "cpu") -> None:
        if n_obs_steps < 1 or n_action_steps < 1:
            raise ValueError(f"need n_obs_steps >= 1 and n_action_steps >= 1, got "
                             f"{n_obs_steps}, {n_action_steps}")
        self.num_envs, self.n_obs_steps, self.n_action_steps = num_envs, n_obs_steps, n_action_steps
        self.device = torch.device(device)
        self.window = ObsWindow(num_envs, n_obs_steps, self.device)
        self.queue = torch.zeros(num_envs, n_action_steps, action_dim, device=self.device)
        self.cursor = torch.full((num_envs,), n_action_steps, device=self.device)

    def reset(self, env_ids: torch.Tensor | None = None) -> None:
        """Those envs (default all) start over: history refilled, queue emptied."""
        ids = slice(None) if env_ids is None else torch.as_tensor(env_ids, device=self.device)
        self.window.reset(ids)
        self.cursor[ids] = self.n_action_steps

    def reads_next(self) -> torch.Tensor:
        """(num_envs,) bool: the envs whose next frame will still be in the window when
        they next plan; the other envs' next frames are pushed out unread."""
        return self.cursor >= self.n_action_steps - self.n_obs_steps + 1

    def act(self, obs: dict[str, torch.Tensor], plan: Planner) -> torch.Tensor:
        """One action per env (num_envs, A); `plan` maps the windows (n, To, ...) of the
        envs that need a new chunk to chunks (n, horizon >= n_action_steps, A)."""
        history = self.window.push(obs)
        need = self.cursor >= self.n_action_steps
        if need.any():
            chunk = plan({k: v[need] for k, v in history.items()})
            if chunk.shape[1] < self.n_action_steps:
                raise ValueError(f"a chunk of {chunk.shape[1]} actions cannot fill "
                                 f"{self.n_action_steps} execution steps")
            self.queue[need] = chunk[:, :self.n_action_steps].to(self.queue)
            self.cursor[need] = 0
        action = self.queue[torch.arange(self.num_envs, device=self.device), self.cursor]
        self.cursor += 1
        return action
