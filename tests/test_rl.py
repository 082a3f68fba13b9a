"""RL: the RSL-RL wrapper, delta actions, reward terms, a PPO smoke run on the CPU backend
and its checkpoint driving an env through the `rl` policy kind."""

import json

import numpy as np
import pytest
import torch

from dexbench.cli.config import ConfigError, load_config
from dexbench.cli.rl import build_env, train
from dexbench.policies import rl as rl_policy
from dexbench.rl.actions import ActionMap, delta_targets
from dexbench.rl.demo_starts import DemoStarts
from dexbench.rl.rewards import RewardTerms, check_terms
from dexbench.rl.vec_env import RslVecEnv
from dexbench.tasks.registry import make_env

_DEFAULT = dict(load_config("rl", []).rl.rewards)  # conf/rl_rewards/default.yaml


def test_delta_targets_scale_by_half_range_and_clip():
    low, high = torch.tensor([-1.0, 0.0]), torch.tensor([1.0, 4.0])
    prev = torch.tensor([[0.0, 3.9]])
    out = delta_targets(prev, torch.tensor([[0.5, 5.0]]), low, high, scale=0.1)
    torch.testing.assert_close(out, torch.tensor([[0.05, 4.0]]))  # 0.1*1*0.5; clipped


@pytest.fixture(scope="module")
def vec():
    cfg = load_config("rl", ["sim.backend=cpu", "num_envs=3", "sim.nthread=1"])
    env = build_env(cfg)
    return RslVecEnv(env, ActionMap(env, "joints", 0.05), _DEFAULT, steps_per_iteration=2)


def test_vec_env_observations_rewards_and_time_outs(vec):
    env = vec.env
    obs = vec.get_observations()
    assert obs["critic"].shape[1] > obs["actor"].shape[1]  # + privileged
    vec.episode_length_buf = torch.full((3,), env.episode_steps - 1)
    action = torch.zeros(3, vec.num_actions)
    action[0] = 1.0
    obs, reward, dones, extras = vec.step(action)
    assert dones.tolist() == [1, 1, 1] and extras["time_outs"].all()
    assert env.steps.tolist() == [0, 0, 0]  # reset inside step
    assert torch.isfinite(reward).all() and obs["actor"].shape[0] == 3
    assert extras["log"]["/reward/action_l2"] < 0
    vec.step(torch.zeros(3, vec.num_actions))
    assert vec.curve.points[-1]["episodes"] == 3  # one iteration of two steps closed


def test_training_episodes_outlast_success_and_count_it(vec, monkeypatch):
    env = vec.env
    real_step = env.step

    def success_in_env_0(actions):
        obs, reward, terminated, truncated, info = real_step(actions)
        terminated[0] = env.steps[0] == 1
        return obs, reward, terminated, truncated, info

    monkeypatch.setattr(env, "step", success_in_env_0)
    short = RslVecEnv(env, vec.action_map, _DEFAULT, steps_per_iteration=2,
                      episode_steps=2)
    zero = torch.zeros(3, short.num_actions)
    _, _, dones, _ = short.step(zero)
    assert dones.tolist() == [0, 0, 0]  # success does not end a training episode
    _, _, dones, extras = short.step(zero)
    assert dones.tolist() == [1, 1, 1] and extras["time_outs"].all()
    assert short.curve.points[-1]["success_rate"] == pytest.approx(1 / 3)
    with pytest.raises(ValueError, match="episode_steps"):
        RslVecEnv(env, vec.action_map, _DEFAULT, 2, episode_steps=env.episode_steps + 1)


def test_synergy_actions_move_the_mount_by_deltas_and_blend_each_hand(vec):
    env = vec.env
    amap = ActionMap(env, "synergy", 0.05, ("power", "pinch"))
    mount = [i for i, a in enumerate(env.embodiment.actuators) if "/hand/" not in a]
    hand = [i for i, a in enumerate(env.embodiment.actuators) if "/hand/" in a]
    assert amap.dim == len(mount) + 2
    prev = env.home_action.float()[None].repeat(3, 1)
    action = torch.zeros(3, amap.dim)
    action[0, :len(mount)] = 1.0
    action[:, -2:] = torch.tensor([[1.0, -1.0], [-1.0, -1.0], [0.0, -1.0]])
    out = amap.targets(prev, action)
    half = (env.action_high - env.action_low)[mount] / 2
    torch.testing.assert_close(out[0, mount] - prev[0, mount].double(), 0.05 * half)
    torch.testing.assert_close(out[1:, mount], prev[1:, mount].double())
    poses = {k: torch.as_tensor(env.embodiment.poses[k])[hand] for k in ("open", "power")}
    clip = lambda x: x.clamp(env.action_low[hand], env.action_high[hand])  # noqa: E731
    torch.testing.assert_close(out[0, hand], clip(poses["power"]))
    torch.testing.assert_close(out[1, hand], clip(poses["open"]))
    torch.testing.assert_close(out[2, hand], clip((poses["open"] + poses["power"]) / 2))
    two = make_env("OpenLaptop", num_envs=1, nthread=1)
    assert ActionMap(two, "synergy", 0.05, ("power",)).dim == 12 + 2  # two wrists, two hands
    with pytest.raises(ValueError, match="synergy"):
        ActionMap(env, "synergy", 0.05, ("fist",))


def test_reward_terms_come_from_the_preset_and_reject_unknown_names():
    assert list(_DEFAULT) == ["task", "lift_when_grasping", "action_l2", "action_rate"]
    sparse = load_config("rl", ["rl_rewards=sparse", "rl.rewards.success.weight=5"]).rl.rewards
    assert sparse.success.weight == 5 and "task" not in sparse
    with pytest.raises(ValueError, match="unknown reward term 'reach'"):
        check_terms({"reach": {"weight": 1.0}})
    with pytest.raises(ValueError, match="needs a weight"):
        check_terms({"task": {}})
    with pytest.raises(ValueError, match=r"no parameter \['tip'\]"):
        check_terms({"lift_when_grasping": {"weight": 1.0, "tip": 3}})


def test_terms_that_do_not_apply_are_left_out_and_weights_scale():
    env = make_env("PushButton", num_envs=2, nthread=1, obs=["state", "contact"])
    obs = env.reset()
    zeros = torch.zeros(2, 4)
    total, terms = RewardTerms(env, _DEFAULT)(torch.ones(2), obs, zeros + 1, zeros)
    assert set(terms) == {"task", "action_l2", "action_rate"}  # nothing to lift
    torch.testing.assert_close(terms["action_rate"], torch.full((2,), -0.005 * 4))
    torch.testing.assert_close(total, 1.0 - 0.005 * 4 * 2 + torch.zeros(2))
    _, doubled = RewardTerms(env, {"task": {"weight": 2.0}})(torch.ones(2), obs, zeros, zeros)
    torch.testing.assert_close(doubled["task"], torch.full((2,), 2.0))


def test_lift_tasks_get_the_grasp_term(vec):
    _, terms = RewardTerms(vec.env, _DEFAULT)(
        torch.zeros(3), vec.env.reset(), torch.zeros(3, vec.num_actions),
        torch.zeros(3, vec.num_actions))
    assert terms["lift_when_grasping"].tolist() == [0.0, 0.0, 0.0]  # resting on the table


def test_ppo_smoke_run_and_rl_policy(tmp_path, monkeypatch):
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path))
    result = train(["sim.backend=cpu", "num_envs=4", "sim.nthread=1", "rl.max_iterations=2",
                    "rl.chunk=1", "rl.network.hidden_dims=[32,32]"])
    run = tmp_path / "rl" / next(p.name for p in (tmp_path / "rl").iterdir())
    assert result["iterations"] == 2 and result["env_steps"] == 2 * 8 * 4
    assert {"model_0.pt", "model_1.pt", "policy.json", "curve.png", "curve.jsonl",
            "metrics.json", "config.yaml"} <= {p.name for p in run.iterdir()}
    assert len((run / "curve.jsonl").read_text().splitlines()) == 2
    spec = rl_policy.spec(str(run), {})
    assert spec.task == "PickCube" and "privileged" not in spec.obs
    env = make_env("PickCube", num_envs=2, obs=list(spec.obs), nthread=1)
    policy = rl_policy.build(str(run / "model_1.pt"), env, "cpu", {})
    obs = env.reset()
    action = policy.act(obs)
    assert action.shape == (2, env.action_dim)
    assert (action >= env.action_low).all() and (action <= env.action_high).all()
    meta = json.loads((run / "policy.json").read_text())
    assert meta["action_mode"] == "synergy" and meta["action_dim"] == 6 + 1
    mount = [i for i, a in enumerate(env.embodiment.actuators) if "/hand/" not in a]
    step = (action - obs["policy"].double()).abs() / (env.action_high - env.action_low)
    assert step[:, mount].max() <= meta["action_scale"] / 2 + 1e-6


def test_ppo_on_the_cpu_backend_repeats_exactly(tmp_path, monkeypatch):
    """Same seed + config on the CPU backend: the same curve and the same weights (the warp
    backend does not promise this: docs/performance.md, determinism on the GPU)."""
    runs = []
    for name in ("a", "b"):
        monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path / name))
        train(["sim.backend=cpu", "num_envs=4", "sim.nthread=1", "rl.max_iterations=2",
               "rl.chunk=1", "rl.network.hidden_dims=[32,32]", "seed=3"])
        runs.append(next((tmp_path / name / "rl").iterdir()))
    curves = [[json.loads(line)["mean_reward"] for line in (r / "curve.jsonl").open()]
              for r in runs]
    assert curves[0] == curves[1] and len(curves[0]) == 2
    weights = [torch.load(r / "model_1.pt", weights_only=False)["actor_state_dict"]
               for r in runs]
    assert all(torch.equal(weights[0][k], weights[1][k]) for k in weights[0])


def test_rl_checkpoint_errors_say_what_to_pass(tmp_path):
    with pytest.raises(rl_policy.CheckpointError, match="checkpoint="):
        rl_policy.spec(None, {})
    with pytest.raises(rl_policy.CheckpointError, match=r"policy\.json"):
        rl_policy.spec(str(tmp_path), {})


def test_sb3_vec_env_truncates_with_the_terminal_observation():
    """SB3's own VecNormalize over our adapter: every episode ends by its time limit and
    hands SB3 the observation it ended on."""
    from stable_baselines3.common.vec_env import VecNormalize

    from dexbench.rl.sb3_env import Sb3VecEnv

    cfg = load_config("rl", ["sim.backend=cpu", "num_envs=2", "sim.nthread=1"])
    env = build_env(cfg)
    vec = RslVecEnv(env, ActionMap(env, "joints", 0.05), _DEFAULT, 2, episode_steps=2)
    venv = VecNormalize(Sb3VecEnv(vec), norm_reward=False)
    first = venv.reset()
    assert first.shape == (2, venv.observation_space.shape[0])
    zeros = np.zeros((2, venv.action_space.shape[0]), dtype=np.float32)
    _, _, dones, _ = venv.step(zeros)
    assert not dones.any()
    obs, reward, dones, infos = venv.step(zeros)
    assert dones.all() and reward.shape == (2,) and obs.shape == first.shape
    for info in infos:
        assert info["TimeLimit.truncated"]
        assert info["terminal_observation"].shape == first.shape[1:]


@pytest.mark.parametrize("algo", ["sac", "sb3_ppo"])
def test_sb3_smoke_run_and_its_policy_in_the_evaluator(tmp_path, monkeypatch, algo):
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path))
    result = train(["sim.backend=cpu", "num_envs=4", "sim.nthread=1", "rl.max_iterations=2",
                    f"rl.algo={algo}", "rl.sb3.batch_size=16", "rl.sb3.net_arch=[16]",
                    "rl.sb3.learning_starts=8", "rl.sb3.buffer_size=1000",
                    "rl.sb3.gradient_steps=1"])
    run = tmp_path / "rl" / next(p.name for p in (tmp_path / "rl").iterdir())
    assert result["algo"] == algo and result["env_steps"] == 2 * 8 * 4
    assert {"model.zip", "vecnormalize.pkl", "policy.json", "curve.png",
            "metrics.json"} <= {p.name for p in run.iterdir()}
    env = make_env("PickCube", num_envs=2, obs=list(rl_policy.spec(str(run), {}).obs),
                   nthread=1)
    action = rl_policy.build(str(run), env, "cpu", {}).act(env.reset())
    assert action.shape == (2, env.action_dim)
    assert (action >= env.action_low).all() and (action <= env.action_high).all()


def test_demo_starts_restore_recorded_frames_and_stay_out_of_the_success_curve(vec, pickcube_demos):
    env = vec.env
    starts = DemoStarts.from_dataset(pickcube_demos, env, fraction=1.0, seed=0)
    short = RslVecEnv(env, vec.action_map, _DEFAULT, steps_per_iteration=1, episode_steps=1,
                      starts=starts)
    zero = torch.zeros(3, short.num_actions)
    obs, _, dones, _ = short.step(zero)  # the first episodes time out; all restart from demos
    assert dones.tolist() == [1, 1, 1] and short.curve.points[-1]["episodes"] == 3
    frames = torch.from_numpy(starts.states)
    state = env.sim_state().cpu()
    match = (state[:, None, :] == frames[None]).all(dim=2)  # (envs, frames)
    assert match.any(dim=1).all()  # every env is exactly at a recorded frame
    chosen = match.float().argmax(dim=1).numpy()
    np.testing.assert_allclose(env.last_action.cpu().numpy(), starts.before[chosen])
    assert env.steps.tolist() == [0, 0, 0]
    assert torch.isfinite(obs["actor"]).all()
    short.step(zero)  # episodes that began at a demonstration frame are not counted
    assert short.curve.points[-1]["episodes"] == 0
    none = DemoStarts.from_dataset(pickcube_demos, env, fraction=0.0, seed=0)
    moved = none.choose(torch.arange(3))
    assert len(moved) == 0


def test_demo_starts_refuse_another_task_and_a_bad_share(pickcube_demos, tmp_path, monkeypatch):
    other = make_env("StackCube", num_envs=1, nthread=1)
    with pytest.raises(ValueError, match=r"collect\.py task=StackCube"):
        DemoStarts.from_dataset(pickcube_demos, other, fraction=0.5, seed=0)
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path))
    common = ["sim.backend=cpu", "num_envs=2", "sim.nthread=1", "rl.max_iterations=1"]
    with pytest.raises(ConfigError, match=r"collect\.py task=PickCube"):
        train([*common, "rl.demo_starts.dataset=auto"])
    with pytest.raises(ConfigError, match=r"\[0, 1\]"):
        train([*common, f"rl.demo_starts.dataset={pickcube_demos}", "rl.demo_starts.fraction=2"])


def test_ppo_smoke_run_with_demo_starts(pickcube_demos, tmp_path, monkeypatch):
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path))
    result = train(["sim.backend=cpu", "num_envs=4", "sim.nthread=1", "rl.max_iterations=2",
                    "rl.chunk=1", "rl.network.hidden_dims=[32,32]", "rl.episode_seconds=0.1",
                    f"rl.demo_starts.dataset={pickcube_demos}", "rl.demo_starts.fraction=0.5"])
    assert result["iterations"] == 2

