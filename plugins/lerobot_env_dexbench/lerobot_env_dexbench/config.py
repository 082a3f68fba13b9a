"""`--env.type=dexbench`: the options of a dexbench env and the features it declares."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
from lerobot.envs.configs import EnvConfig


@EnvConfig.register_subclass("dexbench")
@dataclass
class DexbenchEnv(EnvConfig):
    """A dexbench task on one embodiment with one observation preset.

    `features` and `features_map` (like LeRobot's aloha / pusht configs) are read from a
    built env, so they always match what the env returns and the names of dexbench
    datasets; `fps` is the task's control rate.
    """

    task: str | None = "PickCube"
    fps: int = 60
    embodiment: str | None = None  # None: the task's default embodiment
    obs_type: str = "state"  # a dexbench observation preset, or comma-separated groups
    cameras: str | None = None  # comma-separated camera names; None: the preset's
    observation_width: int = 128
    observation_height: int = 128
    shadows: bool = True  # in camera observations (off renders several times faster on CPU)
    render_mode: str = "rgb_array"
    render_width: int = 256  # render() for lerobot-eval's videos
    render_height: int = 256
    episode_length: int | None = None  # control steps; None: the task's time limit

    def __post_init__(self) -> None:
        from lerobot_env_dexbench.env import describe

        declared = describe(**self.gym_kwargs)
        self.fps = declared.fps
        self.features = dict(declared.features)
        self.features_map = dict(declared.features_map)

    @property
    def gym_kwargs(self) -> dict[str, Any]:
        """The keyword arguments of `lerobot_env_dexbench.env.make_env`."""
        cameras = tuple(c.strip() for c in (self.cameras or "").split(",") if c.strip())
        return {"task": self.task, "embodiment": self.embodiment, "obs": self.obs_type,
                "cameras": cameras or None, "shadows": self.shadows,
                "image_size": (self.observation_width, self.observation_height),
                "render_mode": self.render_mode,
                "render_size": (self.render_width, self.render_height),
                "max_episode_steps": self.episode_length}

    def create_envs(self, n_envs: int, use_async_envs: bool = False
                    ) -> dict[str, dict[int, gym.vector.VectorEnv]]:
        from lerobot_env_dexbench.env import make_vector_env

        return {self.type: {0: make_vector_env(self.gym_kwargs, n_envs, use_async_envs)}}
