"""Stable-Baselines3's `VecEnv` over the batched `DexEnv`, through `RslVecEnv`.

The same actor observations, delta actions in [-1, 1], reward terms, training episode
length and success curve as PPO on RSL-RL, so SB3's algorithms (SAC, its PPO) compare
with it on equal terms. Arrays cross to NumPy at this boundary, as SB3 expects; an
episode ends only by its time limit, so every done carries `TimeLimit.truncated` and its
`terminal_observation` for bootstrapping.
"""

from __future__ import annotations

import pathlib
import pickle
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.base_class import BaseAlgorithm
from stable_baselines3.common.vec_env import VecEnv, VecNormalize

from dexbench.rl.vec_env import RslVecEnv


class Sb3VecEnv(VecEnv):
    def __init__(self, vec: RslVecEnv) -> None:
        self.vec = vec
        dim = int(vec.get_observations()["actor"].shape[1])
        obs_space = gym.spaces.Box(-np.inf, np.inf, (dim,), np.float32)
        act_space = gym.spaces.Box(-1.0, 1.0, (vec.num_actions,), np.float32)
        super().__init__(vec.num_envs, obs_space, act_space)
        self._actions: torch.Tensor | None = None

    def reset(self) -> np.ndarray:
        return self._numpy(self.vec.get_observations()["actor"])

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = torch.as_tensor(actions, dtype=torch.float32, device=self.vec.device)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict]]:
        obs, reward, done, extras = self.vec.step(self._actions)
        dones = done.bool().cpu().numpy()
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if dones.any():
            final = self._numpy(extras["final_actor"])
            for row, i in enumerate(np.flatnonzero(dones)):
                infos[i] = {"terminal_observation": final[row], "TimeLimit.truncated": True}
        return (self._numpy(obs["actor"]), reward.float().cpu().numpy(), dones, infos)

    @staticmethod
    def _numpy(x: torch.Tensor) -> np.ndarray:
        return x.float().cpu().numpy()

    def close(self) -> None:
        """The DexEnv holds no external resources."""

    def get_attr(self, attr_name: str, indices: Sequence[int] | None = None) -> list[Any]:
        return [getattr(self, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Sequence[int] | None = None,
                 ) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs,
                   ) -> list[Any]:
        fn = getattr(self, method_name)
        return [fn(*method_args, **method_kwargs) for _ in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices=None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Sequence[int] | int | None) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        return [indices] if isinstance(indices, int) else indices


ALGOS = {"sac": SAC, "sb3_ppo": PPO}  # rl.algo -> Stable-Baselines3 class
MODEL_FILE = "model.zip"
NORM_FILE = "vecnormalize.pkl"  # SB3's observation statistics, applied again at evaluation


def load_sb3(run: pathlib.Path, algo: str, device: torch.device | str,
             ) -> tuple[BaseAlgorithm, VecNormalize]:
    """A trained SB3 model and its observation normalizer (without an env)."""
    model = ALGOS[algo].load(run / MODEL_FILE, device=device)
    with open(run / NORM_FILE, "rb") as f:
        norm = pickle.load(f)  # our own run folder: trusted
    return model, norm
