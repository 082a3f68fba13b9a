"""The Gymnasium wrapper, checked with the peers' own code: Gymnasium's env checker,
`make`, `TimeLimit` and vector envs, and LeRobot's evaluator rollout."""

import warnings

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.utils.env_checker import check_env

import dexbench  # noqa: F401  (registers the gym ids)
from dexbench.envs.gym_env import DexGymEnv
from dexbench.envs.scene import CONTACT_FORCE_CLIP
from dexbench.envs.variation import PhysicalVariation
from dexbench.tasks.registry import TASKS, make_env

ENV_ID = "dexbench/PickCube-v0"
SMALL = {"image_size": (64, 64), "num_points": 64, "shadows": False}  # fast to render
# What check_env may say about our env: the physics is unbounded, and actions are absolute
# joint targets (not normalised to [-1, 1]), both by design.
ALLOWED = (
    "A Box observation space minimum value is -infinity",
    "A Box observation space maximum value is infinity",
    "For Box action spaces, we recommend using a symmetric and normalized space",
)
# Gymnasium's own remark whenever check_env is given a wrapped env (gym.make's chain).
WRAPPED = "is different from the unwrapped version"


def _unexpected_warnings(env: gym.Env, allowed: tuple[str, ...] = ALLOWED) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env)
    return sorted({str(w.message) for w in caught
                   if not any(text in str(w.message) for text in allowed)})


@pytest.mark.parametrize("preset", ["state", "rgb", "pointcloud"])
def test_gymnasium_env_checker_passes(preset):
    env = gym.make(ENV_ID, obs=preset, **SMALL)
    assert _unexpected_warnings(env.unwrapped) == []
    assert _unexpected_warnings(env, (*ALLOWED, WRAPPED)) == []
    env.close()


def test_the_checker_test_fails_on_a_space_that_lies():
    env = gym.make(ENV_ID).unwrapped
    env.observation_space["state"] = gym.spaces.Box(-np.inf, np.inf, (7,), np.float64)
    assert any("dtype to be float64" in m for m in _unexpected_warnings(env))


def test_observation_space_is_exactly_what_comes_back():
    env = gym.make(ENV_ID, obs=["policy", "contact", "rgb", "depth", "pointcloud"],
                   image_size=(48, 32), num_points=32)
    space = env.observation_space
    first, _ = env.reset(seed=0)
    after, *_ = env.step(env.action_space.sample())
    for obs in (first, after):
        assert obs.keys() == space.keys()
        for key, value in obs.items():
            assert (value.dtype, value.shape) == (space[key].dtype, space[key].shape), key
        assert obs in space
    rgb, depth = space["rgb/front"], space["depth/front"]
    assert rgb.dtype == np.uint8 and rgb.shape == (32, 48, 3)
    assert (rgb.low == 0).all() and (rgb.high == 255).all()
    assert depth.dtype == np.float32 and (depth.low == 0).all() and np.isinf(depth.high).all()
    assert (space["contact"].high == CONTACT_FORCE_CLIP).all()
    np.testing.assert_array_equal(space["policy"].low, env.action_space.low)
    np.testing.assert_array_equal(space["policy"].high, env.action_space.high)


def test_rgb_array_render_shows_the_front_camera():
    env = gym.make(ENV_ID, obs=["rgb"], image_size=(64, 48), render_mode="rgb_array",
                   render_size=(64, 48))
    assert env.metadata["render_modes"] == ["rgb_array"]
    assert env.metadata["render_fps"] == 60  # the control rate
    obs, _ = env.reset(seed=1)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.shape == (48, 64, 3) and frame.std() > 5
    np.testing.assert_array_equal(frame, obs["rgb/front"])
    env.close()
    env.close()  # closing twice is allowed

    default = gym.make(ENV_ID, render_mode="rgb_array")
    default.reset(seed=1)
    assert default.render().shape == (480, 480, 3)
    default.close()


def test_render_mode_none_and_unsupported_modes():
    env = gym.make(ENV_ID)
    assert env.render_mode is None
    with pytest.warns(UserWarning, match="render_mode='rgb_array'"):
        assert env.unwrapped.render() is None
    with pytest.raises(ValueError, match="rgb_array"):
        gym.make(ENV_ID, render_mode="human")
    with pytest.raises(ValueError, match="render_size"):
        gym.make(ENV_ID, render_mode="rgb_array", render_size=(4096, 64))


def test_max_episode_steps_is_the_task_time_limit():
    for name, cls in TASKS.items():
        assert gym.spec(f"dexbench/{name}-v0").max_episode_steps == round(
            cls.episode_seconds * 60), name
    env = gym.make(ENV_ID)
    assert env.spec.max_episode_steps == env.unwrapped.env.episode_steps == 1200


def test_only_the_time_limit_wrapper_truncates():
    env = gym.make(ENV_ID, max_episode_steps=6)
    env.unwrapped.env.episode_steps = 3  # the DexEnv's own limit must not cut in
    env.reset(seed=0)
    hold = env.unwrapped.env.home_action.numpy().astype(np.float32)
    assert [env.step(hold)[3] for _ in range(6)] == [False] * 5 + [True]
    env.reset()
    assert env.step(hold)[3] is False


@pytest.mark.parametrize("preset, key", [("rgb", "rgb/front"), ("pointcloud", "pointcloud")])
def test_same_seed_same_observations_in_a_fresh_env(preset, key):
    runs = []
    for _ in range(2):
        env = gym.make(ENV_ID, obs=preset, **SMALL)
        env.action_space.seed(0)
        first, _ = env.reset(seed=3)
        stepped, *_ = env.step(env.action_space.sample())
        other, _ = env.reset(seed=4)
        runs.append((first, stepped, other))
    for one, two in zip(*runs, strict=True):
        np.testing.assert_equal(one, two)
    first, _, other = runs[0]
    assert not np.array_equal(first[key], other[key])  # another seed, another scene


def test_seeded_reset_repeats_observation_noise():
    env = DexGymEnv(make_env("PickCube", physical=PhysicalVariation(enabled=True,
                                                                      obs_noise=0.01)))
    first, _ = env.reset(seed=2)
    noisy, _ = env.reset()
    again, _ = env.reset(seed=2)
    np.testing.assert_array_equal(again["proprio"], first["proprio"])
    assert not np.array_equal(noisy["proprio"], first["proprio"])


class _LiftCubePolicy(torch.nn.Module):
    """Holds the home pose and teleports the cube up each step: success on demand."""

    def __init__(self, env: gym.vector.VectorEnv) -> None:
        super().__init__()
        self.dex = env.envs[0].unwrapped.env
        cube = self.dex.scene.model.joint("cube/free")
        self.z, self.dof = cube.qposadr[0] + 2, cube.dofadr[0]

    def reset(self) -> None:
        pass

    def select_action(self, observation) -> torch.Tensor:
        self.dex.sim.field("qpos")[0, self.z] = 0.9
        self.dex.sim.field("qvel")[0, self.dof:self.dof + 6] = 0.0
        self.dex.sim.forward(torch.arange(1))
        return self.dex.home_action.float()[None]


def test_success_reaches_lerobots_evaluator_as_is_success():
    from lerobot.scripts.lerobot_eval import rollout

    env = gym.vector.SyncVectorEnv([lambda: gym.make(ENV_ID)])
    # What LeRobot's rollout runs to, and hands language-conditioned policies.
    assert env.call("_max_episode_steps") == (1200,)
    assert env.call("task_description") == ("Pick up the cube and lift it above the table.",)
    assert env.call("task") == ("PickCube",)
    same = lambda x: x  # noqa: E731  (LeRobot's processor pipelines, as identities)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = rollout(env, _LiftCubePolicy(env), same, same, same, same, seeds=[0])
    assert not [w for w in caught if "task_description" in str(w.message)]
    success = out["success"][0]
    assert len(success) == 10 and success[-1]  # terminated after 10 steps held
    env.close()
