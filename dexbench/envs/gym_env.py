"""Gymnasium single-environment wrapper, registered as `dexbench/<Task>-v0`."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv


class DexGymEnv(gym.Env):
    """One `DexEnv` world behind the Gymnasium API (numpy in, numpy out)."""

    metadata: ClassVar[dict] = {"render_modes": []}

    def __init__(self, env: DexEnv) -> None:
        if env.num_envs != 1:
            raise ValueError("DexGymEnv wraps a DexEnv with num_envs=1; use DexEnv for batches")
        self.env = env
        low = env.action_low.cpu().numpy().astype(np.float32)
        high = env.action_high.cpu().numpy().astype(np.float32)
        self.action_space = gym.spaces.Box(low, high, dtype=np.float32)
        self.observation_space = gym.spaces.Dict({
            k: gym.spaces.Box(-np.inf, np.inf, shape, np.float32)
            for k, shape in env.obs_shapes().items()
        })

    @staticmethod
    def _np(obs: dict[str, torch.Tensor]) -> dict[str, np.ndarray]:
        return {k: v[0].cpu().numpy().copy() for k, v in obs.items()}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is not None:
            self.env.reseed(seed)
        return self._np(self.env.reset()), {}

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(
            torch.as_tensor(np.asarray(action, dtype=np.float64))[None])
        return (self._np(obs), float(reward[0]), bool(terminated[0]), bool(truncated[0]),
                {"success": bool(info["success"][0])})
