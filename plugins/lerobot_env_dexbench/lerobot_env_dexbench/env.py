"""dexbench tasks as LeRobot's evaluator expects an env: keys, features and vector envs.

LeRobot's `preprocess_observation` turns `agent_pos` into `observation.state`,
`environment_state` into `observation.environment_state`, each camera of the `pixels` dict
into `observation.images.<camera>` and any other key into `observation.<key>`. The keys
here are chosen so that those names are exactly dexbench's dataset features
(`dexbench.data.features`): a policy trained with `lerobot-train` on a dexbench dataset
finds every input it was trained on. `pixels` is a dict even for one camera, since a bare
array would become `observation.image`, a name no dexbench dataset has.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
from gymnasium.vector import AutoresetMode
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.utils import freeze_after_episode_end
from lerobot.utils.constants import ACTION, OBS_IMAGES, OBS_STR

from dexbench.data.features import feature_key
from dexbench.envs.gym_env import DexGymEnv
from dexbench.envs.observations import PRESETS, resolve_preset
from dexbench.tasks.registry import make_env as make_dex_env

PIXELS = "pixels"
AGENT_POS = "agent_pos"


def env_key(group: str) -> str:
    """The key of a (non-camera) observation group in this env's observations."""
    return AGENT_POS if group == "proprio" else feature_key(group).removeprefix(f"{OBS_STR}.")


def camera_key(group: str) -> str:
    """The `pixels` entry of an `rgb/<camera>` group (`right/hand/wrist_cam` ->
    `right_hand_wrist_cam`, as in datasets)."""
    return feature_key(group).removeprefix(f"{OBS_IMAGES}.")


class LeRobotObservations(gym.ObservationWrapper):
    """A `DexGymEnv`'s observation groups under LeRobot's env keys.

    `paths` maps each entry (`agent_pos`, `pixels/front`, ...) to its dexbench group.
    """

    def __init__(self, env: DexGymEnv) -> None:
        super().__init__(env)
        space = env.observation_space
        self._images = {g: camera_key(g) for g in space if g.startswith("rgb/")}
        self._others = {g: env_key(g) for g in space if not g.startswith("rgb/")}
        spaces: dict[str, gym.Space] = {k: space[g] for g, k in self._others.items()}
        if self._images:
            spaces[PIXELS] = gym.spaces.Dict({k: space[g] for g, k in self._images.items()})
        self.observation_space = gym.spaces.Dict(spaces)
        self.paths = {**{k: g for g, k in self._others.items()},
                      **{f"{PIXELS}/{k}": g for g, k in self._images.items()}}

    def observation(self, observation: dict[str, Any]) -> dict[str, Any]:
        out = {k: observation[g] for g, k in self._others.items()}
        if self._images:
            out[PIXELS] = {k: observation[g] for g, k in self._images.items()}
        return out


def make_env(task: str, embodiment: str | None = None, obs: str = "state",
             cameras: tuple[str, ...] | None = None, image_size: tuple[int, int] = (128, 128),
             shadows: bool = True, render_mode: str | None = "rgb_array",
             render_size: tuple[int, int] = (256, 256),
             max_episode_steps: int | None = None) -> gym.Env:
    """One env: `DexGymEnv` (no observation history: LeRobot policies keep their own)
    with LeRobot's keys, truncated at `max_episode_steps` (None: the task's time limit).
    `obs` is a preset or comma-separated groups; sizes are (width, height)."""
    groups = obs if obs in PRESETS else [g.strip() for g in obs.split(",") if g.strip()]
    preset = resolve_preset(groups)
    if "depth" in preset.groups:
        raise ValueError(f"obs_type={obs!r} holds depth images, which LeRobot's env "
                         "observations cannot carry; choose a preset without depth (state, "
                         "rgb, 3view_rgb, pointcloud)")
    dex = make_dex_env(task, embodiment, num_envs=1, obs=groups, history=0,
                       cameras=list(cameras) if cameras else None, image_size=image_size,
                       shadows=shadows)
    env = LeRobotObservations(DexGymEnv(dex, render_mode, render_size, shadows))
    return gym.wrappers.TimeLimit(env, max_episode_steps or dex.episode_steps)


def make_vector_env(kwargs: dict[str, Any], n_envs: int,
                    use_async: bool) -> gym.vector.VectorEnv:
    """`n_envs` envs as LeRobot's own env configs batch them: subprocesses started by
    forkserver when asked (and more than one), autoreset in the same step, and an env
    whose episode ended frozen (LeRobot's rollout steps every env until the last ends)."""
    fns = [freeze_after_episode_end(functools.partial(make_env, **kwargs))
           for _ in range(n_envs)]
    if use_async and n_envs > 1:
        return gym.vector.AsyncVectorEnv(fns, context="forkserver",
                                         autoreset_mode=AutoresetMode.SAME_STEP)
    return gym.vector.SyncVectorEnv(fns, autoreset_mode=AutoresetMode.SAME_STEP)


@dataclass(frozen=True)
class EnvFeatures:
    """What an `EnvConfig` declares: control rate, features and their dataset names."""

    fps: int
    features: dict[str, PolicyFeature]
    features_map: dict[str, str]


@functools.cache
def describe(**kwargs: Any) -> EnvFeatures:
    """The features of the env `make_env(**kwargs)` builds, read from one built env."""
    env = make_env(**{**kwargs, "render_mode": None})
    try:
        space = env.observation_space
        features = {ACTION: PolicyFeature(type=FeatureType.ACTION, shape=env.action_space.shape)}
        features_map = {ACTION: ACTION}
        for path, group in env.get_wrapper_attr("paths").items():
            key, _, camera = path.partition("/")
            box = space[key][camera] if camera else space[key]
            kind = (FeatureType.VISUAL if camera else
                    FeatureType.ENV if group == "state" else FeatureType.STATE)
            features[path] = PolicyFeature(type=kind, shape=box.shape)
            features_map[path] = feature_key(group)
        return EnvFeatures(env.metadata["render_fps"], features, features_map)
    finally:
        env.close()
