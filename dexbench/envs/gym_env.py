"""Gymnasium single-environment wrapper, registered as `dexbench/<Task>-v0`.

It follows Gymnasium's conventions so that RL/IL code written for Gymnasium runs as is:
the observation space is exactly what `reset` and `step` return (uint8 images in
[0, 255], depth >= 0 m, contact forces within their clip, the previous action within the
action bounds), `info["is_success"]` mirrors `info["success"]` (the key LeRobot's
evaluator reads), and `render_mode="rgb_array"` renders the front camera. The time limit
belongs to Gymnasium's `TimeLimit` wrapper (`max_episode_steps`, registered as the
task's time limit), so this env never truncates by itself: one owner, no double
truncation. Actions stay absolute joint targets, as everywhere in dexbench.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.envs.scene import CONTACT_FORCE_CLIP
from dexbench.sim.cpu import CpuBackend
from dexbench.sim.factory import make_renderer

RENDER_SIZE = (480, 480)  # (width, height): the default of Gymnasium's MuJoCo envs
RENDER_CAMERA = "front"

Bound = float | np.ndarray


def _bounds(group: str, env: DexEnv) -> tuple[Bound, Bound]:
    """The range an observation group's values are known to lie in (else unbounded)."""
    if group.startswith("rgb/"):
        return 0, 255
    if group.startswith("depth/"):
        return 0.0, np.inf
    if group == "contact":
        return -CONTACT_FORCE_CLIP, CONTACT_FORCE_CLIP
    if group == "policy":  # the previous action, which the env clips to the action bounds
        return env.action_low.cpu().numpy(), env.action_high.cpu().numpy()
    return -np.inf, np.inf


def observation_space(env: DexEnv, obs: dict[str, np.ndarray]) -> gym.spaces.Dict:
    """Boxes with the dtype and shape of an actual observation and each group's bounds."""
    boxes = {}
    for group, value in obs.items():
        low, high = (np.broadcast_to(b, value.shape).astype(value.dtype)
                     for b in _bounds(group, env))
        boxes[group] = gym.spaces.Box(low, high, value.shape, value.dtype)
    return gym.spaces.Dict(boxes)


class DexGymEnv(gym.Env):
    """One `DexEnv` world behind the Gymnasium API (numpy in, numpy out).

    Made through `gymnasium.make`, the task's time limit truncates episodes; built
    directly, wrap it in `gymnasium.wrappers.TimeLimit(env, env.env.episode_steps)`.
    `render_size` is (width, height) of `render()`'s image.
    """

    metadata: ClassVar[dict] = {"render_modes": ["rgb_array"], "render_fps": 60}

    def __init__(self, env: DexEnv, render_mode: str | None = None,
                 render_size: tuple[int, int] = RENDER_SIZE, render_shadows: bool = True,
                 ) -> None:
        if env.num_envs != 1:
            raise ValueError("DexGymEnv wraps a DexEnv with num_envs=1; use DexEnv for batches")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode={render_mode!r} is not supported; use "
                             f"{self.metadata['render_modes']} or None")
        frame = env.scene.model.vis.global_  # the offscreen buffer the renderer draws into
        if not (0 < render_size[0] <= frame.offwidth and 0 < render_size[1] <= frame.offheight):
            raise ValueError(f"render_size={tuple(render_size)} (width, height) must lie within "
                             f"1..{frame.offwidth} x 1..{frame.offheight}")
        self.env = env
        self.render_mode = render_mode
        self.render_size = tuple(render_size)
        # An int, as Gymnasium's own envs: video writers take it as a rational.
        self.metadata = {**self.metadata, "render_fps": round(env.physics.control_hz)}
        self.render_shadows = render_shadows
        self._renderer = None
        low = env.action_low.cpu().numpy().astype(np.float32)
        high = env.action_high.cpu().numpy().astype(np.float32)
        self.action_space = gym.spaces.Box(low, high, dtype=np.float32)
        self.observation_space = observation_space(env, self._np(env.reset()))
        env.reseed(env.seed)  # the first reset() is episode 0 again

    @staticmethod
    def _np(obs: dict[str, torch.Tensor]) -> dict[str, np.ndarray]:
        return {k: v[0].cpu().numpy().copy() for k, v in obs.items()}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        if seed is not None:
            self.env.reseed(seed)
        return self._np(self.env.reset()), {}

    def step(self, action):
        obs, reward, terminated, _, info = self.env.step(
            torch.as_tensor(np.asarray(action, dtype=np.float64))[None])
        success = bool(info["success"][0])
        return (self._np(obs), float(reward[0]), bool(terminated[0]), False,
                {"success": success, "is_success": success})

    @property
    def task(self) -> str:
        """The task's name (LeRobot's evaluator reads `task` and `task_description`)."""
        return self.env.task.name

    @property
    def task_description(self) -> str:
        """The task's language instruction, for language-conditioned policies."""
        return self.env.task.instruction

    def render(self) -> np.ndarray | None:
        """The front camera's view as (height, width, 3) uint8 (`render_mode="rgb_array"`)."""
        if self.render_mode is None:
            gym.logger.warn("render() needs a render mode: make the env with "
                            "render_mode='rgb_array'")
            return None
        if self._renderer is None:  # the OpenGL (or ray-tracing) context only when asked for
            kind = "cpu" if isinstance(self.env.sim, CpuBackend) else "warp"
            self._renderer = make_renderer(self.env.sim, *self.render_size, kind=kind,
                                           shadows=self.render_shadows)
        frames = self._renderer.render([RENDER_CAMERA], rgb=True, depth=False)
        return frames[RENDER_CAMERA].rgb[0].cpu().numpy().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
