"""DexEnv behaviour: determinism, resets, action validation, observations (the Gymnasium
wrapper: test_gym_env.py)."""

import numpy as np
import pytest
import torch

from dexbench.embodiments.builder import UnknownEmbodimentError
from dexbench.envs.dex_env import DexEnv, InvalidActionError
from dexbench.envs.scene import InfeasibleTaskError
from dexbench.tasks.primitive import PickCube
from dexbench.tasks.registry import UnknownTaskError, make_env


def _rollout(env: DexEnv, steps: int, seed: int = 1) -> np.ndarray:
    env.reset()
    gen = torch.Generator().manual_seed(seed)
    span = env.action_high - env.action_low
    states = []
    for _ in range(steps):
        noise = torch.randn(env.num_envs, env.action_dim, generator=gen, dtype=torch.float64)
        env.step(env.home_action + 0.1 * span * noise)
        states.append(env.sim.get_state().numpy())
    return np.stack(states)


def test_same_seed_is_bit_identical_across_thread_counts():
    one = _rollout(make_env("PickCube", num_envs=4, seed=7, nthread=1), 30)
    two = _rollout(make_env("PickCube", num_envs=4, seed=7, nthread=2), 30)
    assert one.shape[0] == 30 and np.isfinite(one).all()
    np.testing.assert_array_equal(one, two)


def test_seed_changes_reset_distribution_and_envs_differ():
    a = make_env("PickCube", num_envs=3, seed=0)
    b = make_env("PickCube", num_envs=3, seed=1)
    cube_a = a.reset()["state"][:, :3]
    cube_b = b.reset()["state"][:, :3]
    assert not torch.equal(cube_a, cube_b)
    assert len({tuple(x.tolist()) for x in cube_a}) == 3
    assert torch.equal(cube_a, a.reset()["state"][:, :3]) is False  # next episode differs
    a.reseed(0)
    assert torch.equal(cube_a, a.reset()["state"][:, :3])


def test_subset_reset_leaves_other_envs_untouched():
    env = make_env("PickCube", num_envs=4, seed=3)
    _rollout(env, 10)
    before = env.sim.get_state().clone()
    steps_before = env.steps.clone()
    env.reset([0, 2])
    after = env.sim.get_state()
    torch.testing.assert_close(after[[1, 3]], before[[1, 3]], rtol=0, atol=0)
    assert not torch.equal(after[[0, 2]], before[[0, 2]])
    assert env.steps.tolist() == [0, steps_before[1].item(), 0, steps_before[3].item()]
    cube_z = env.view.body_pos("cube")[[0, 2], 2]
    torch.testing.assert_close(cube_z, torch.full_like(cube_z, 0.625))


@pytest.mark.parametrize(
    "bad, match",
    [
        (lambda e: torch.zeros(e.num_envs, e.action_dim + 1), "shape"),
        (lambda e: torch.zeros(e.action_dim), "shape"),
        (lambda e: torch.full((e.num_envs, e.action_dim), float("nan")), "NaN or inf"),
        (lambda e: torch.full((e.num_envs, e.action_dim), float("inf")), "NaN or inf"),
    ],
)
def test_invalid_actions_are_rejected_without_stepping(bad, match):
    env = make_env("PickCube", num_envs=2)
    env.reset()
    state = env.sim.get_state().clone()
    with pytest.raises(InvalidActionError, match=match):
        env.step(bad(env))
    assert torch.equal(state, env.sim.get_state())


def test_actions_are_clipped_to_ctrl_range():
    env = make_env("PickCube", num_envs=1)
    env.reset()
    env.step(torch.full((1, env.action_dim), 1e3, dtype=torch.float64))
    torch.testing.assert_close(env.sim.field("ctrl")[0], env.action_high)


def test_unknown_names_and_infeasible_pairs_raise_clear_errors():
    with pytest.raises(UnknownTaskError, match="PickCube"):
        make_env("NoSuchTask")
    with pytest.raises(UnknownEmbodimentError, match="list embodiments"):
        make_env("PickCube", "floating_hook")

    class TwoHanded(PickCube):
        bimanual = True

    with pytest.raises(InfeasibleTaskError, match="bimanual_floating_shadow"):
        DexEnv(TwoHanded(), "floating_shadow")


def test_state_preset_shapes():
    env = make_env("PickCube", num_envs=2)
    obs = env.reset()
    nu, njoint = env.action_dim, len(env.embodiment.proprio_joints)
    ntips = len(env.embodiment.sides["right"].fingertip_sites)
    assert {k: tuple(v.shape) for k, v in obs.items()} == {
        "policy": (2, nu), "proprio": (2, njoint), "contact": (2, 3 * ntips), "state": (2, 7)}
    assert all(v.dtype == torch.float32 for v in obs.values())
    torch.testing.assert_close(obs["policy"], env.home_action.float().expand(2, -1))
    with pytest.raises(ValueError, match="unknown observation preset"):
        make_env("PickCube", obs="thermal")


def test_privileged_group_and_history_stacking():
    env = make_env("PickCube", num_envs=2, obs=["proprio", "privileged"], history=2)
    obs = env.reset()
    assert obs["proprio"].shape == (2, 2, len(env.embodiment.proprio_joints))
    torch.testing.assert_close(obs["proprio"][:, 0], obs["proprio"][:, 1])
    first = obs["proprio"][:, 1].clone()
    obs, *_ = env.step(env.home_action.repeat(2, 1) + 0.05)
    torch.testing.assert_close(obs["proprio"][:, 0], first)
    nlinks = 1 + len(env.embodiment.sides["right"].fingertip_sites)
    nv = len(env.embodiment.proprio_joints)
    assert obs["privileged"].shape == (2, 2, nv + 13 * nlinks + 6)


def test_pickcube_success_predicate_and_time_limit():
    env = make_env("PickCube", num_envs=3, auto_reset=False)
    env.reset()
    qpos = env.sim.field("qpos")
    z = env.scene.model.joint("cube/free").qposadr[0] + 2
    qpos[0, z] += 0.25   # lifted 0.25 m: success
    qpos[1, z] += 0.15   # lifted 0.15 m: not yet
    env.sim.forward(torch.arange(3))
    assert env.task.success(env.view).tolist() == [True, False, False]
    env.steps[:] = env.episode_steps - 1
    _, reward, _, truncated, info = env.step(env.home_action.repeat(3, 1))
    assert truncated.all() and reward.shape == (3,) and info["success"].dtype == torch.bool
