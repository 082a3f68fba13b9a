"""Training resets that start from expert demonstrations (reference-state initialisation).

PPO on a grasp-and-lift task learns only once some episode has lifted the object, and with
a freshly initialised policy that is a rare event: whether and when it first happens
decides whether a run learns at all. Starting a share of the training episodes from a
random frame of a recorded expert demonstration (the same task and embodiment, restored
exactly from its simulator state) puts the policy next to the grasp and the lift from the
first iteration. The other episodes, and every evaluation, start from the task's own reset.

An episode started this way is left out of the training success curve: it may begin with
the object already lifted, so it says nothing about the policy's own success.
"""

from __future__ import annotations

import pathlib

import numpy as np
import torch

from dexbench.data.lerobot_io import read_episodes
from dexbench.data.meta import read_meta
from dexbench.envs.dex_env import DexEnv, Obs


class DemoStarts:
    """The frames of a dataset's demonstrations as reset states for one env."""

    def __init__(self, keys: np.ndarray, states: np.ndarray, before: np.ndarray,
                 episode: np.ndarray, fraction: float, seed: int) -> None:
        if not 0.0 <= fraction <= 1.0:
            raise ValueError(f"the share of demonstration starts must be in [0, 1], got {fraction}")
        self.keys = keys  # (E, 3) episode keys
        self.states = states  # (F, S) float64 simulator states, every frame of every episode
        self.before = before  # (F, A) the action applied before each frame
        self.episode = episode  # (F,) which episode each frame belongs to
        self.fraction = fraction
        self._rng = np.random.default_rng(seed)

    @classmethod
    def from_dataset(cls, root: pathlib.Path, env: DexEnv, fraction: float,
                     seed: int) -> DemoStarts:
        """Every frame of the `collect.py` dataset at `root`, which must be of `env`'s task
        and embodiment."""
        meta = read_meta(root)
        recorded = (meta.get("task"), meta.get("embodiment"))
        if recorded != (env.task.name, env.embodiment.name):
            raise ValueError(f"{root} holds {recorded[0]} on {recorded[1]}, not "
                             f"{env.task.name} on {env.embodiment.name}; collect one with "
                             f"`python collect.py task={env.task.name} "
                             f"embodiment={env.embodiment.name}`")
        episodes = read_episodes(root, meta, observations=False)
        home = env.home_action.float().cpu().numpy()
        before = [np.concatenate([home[None], ep.actions[:-1]]) for ep in episodes]
        return cls(np.array([ep.key for ep in episodes], dtype=np.int64),
                   np.concatenate([ep.states for ep in episodes]),
                   np.concatenate(before).astype(np.float32),
                   np.concatenate([np.full(ep.length, i) for i, ep in enumerate(episodes)]),
                   fraction, seed)

    @property
    def num_frames(self) -> int:
        return len(self.states)

    def choose(self, ids: torch.Tensor) -> torch.Tensor:
        """The `fraction` share of the envs `ids` (due for a reset) to start from
        demonstration frames, drawn anew each call."""
        ids = ids.cpu()
        return ids[torch.from_numpy(self._rng.random(len(ids)) < self.fraction)]

    def start(self, env: DexEnv, ids: torch.Tensor) -> Obs:
        """Reset the envs `ids` into random demonstration frames (their episodes' resets,
        then the frames' states); return all envs' observations."""
        frames = self._rng.integers(self.num_frames, size=len(ids))
        obs = env.reset_to(ids, self.keys[self.episode[frames]])
        restored = env.restore(ids, self.states[frames], self.before[frames])
        dev = ids.to(env.device)
        for group, value in restored.items():
            obs[group][dev] = value
        return obs
