"""Demonstrations: collection, LeRobot format, state and action replay, resume, validation.

Test doubles stand in for the scripted experts: `CubeLifter` drives PickCube to success
by lifting the cube through the simulator state (in even envs; odd envs time out), and
`Sway` only acts, on a PickCube whose lift threshold is forced below zero so that it
succeeds after one step.
"""

import json
import pathlib
import shutil

import mujoco
import numpy as np
import pyarrow.parquet as pq
import pytest
import torch
from lerobot.datasets import LeRobotDataset

from dexbench.cli import collect as collect_cli
from dexbench.cli.config import ConfigError
from dexbench.cli.introspect import main as dexbench_main
from dexbench.cli.replay import main as replay_main
from dexbench.data.collect import CollectSettings, Staging, collect
from dexbench.data.lerobot_io import read_episodes
from dexbench.data.meta import DatasetError, env_from_config, read_meta
from dexbench.data.replay import replay_states
from dexbench.data.validate import validate_dataset
from dexbench.envs.dex_env import STATE_SPEC
from dexbench.sim.backend import state_layout
from dexbench.sim.cpu import CpuBackend
from dexbench.tasks.primitive import PickCube
from dexbench.tasks.registry import TASKS, make_env

SMALL = {"image_size": (32, 24), "nthread": 1}


class Sway:
    """Acts only: sways every actuator around the home pose."""

    def __init__(self, env):
        self.env = env
        self.t = torch.zeros(env.num_envs)

    def reset(self, env_ids):
        self.t[env_ids] = 0

    def act(self):
        self.t += 1
        span = self.env.action_high - self.env.action_low
        return self.env.home_action + 0.05 * span * torch.sin(0.3 * self.t[:, None])


class CubeLifter(Sway):
    """Lifts the cube 2 cm per step through the simulator state, in even envs only."""

    def act(self):
        model = self.env.scene.model
        joint = model.joint(self.env.task.objects["cube"].free_joint)
        lift = torch.arange(self.env.num_envs) % 2 == 0
        self.env.sim.field("qpos")[lift, int(joint.qposadr[0]) + 2] += 0.02
        self.env.sim.field("qvel")[lift, int(joint.dofadr[0]):int(joint.dofadr[0]) + 6] = 0
        return super().act()


@pytest.fixture(scope="module")
def demos(tmp_path_factory):
    """A small collected dataset and the episodes as the collector handed them over."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(PickCube, "episode_seconds", 0.4)
        env = make_env("PickCube", num_envs=4, seed=3, nthread=1)
    root = tmp_path_factory.mktemp("demos") / "PickCube"
    kept = []
    stats = collect(env, CubeLifter(env), root, CollectSettings(3, 20, post_success_steps=3),
                    {"note": "test"}, on_episode=kept.append, progress=False)
    return root, kept, stats


def test_every_task_has_its_own_instruction():
    instructions = [cls.instruction for cls in TASKS.values()]
    assert len(instructions) == len(set(instructions)) == len(TASKS)
    assert all(i[0].isupper() and i.endswith(".") and len(i.split()) >= 3 for i in instructions)


def test_state_spec_columns_match_mj_get_state():
    model = mujoco.MjModel.from_xml_string("""
        <mujoco><size nuserdata="2"/><worldbody>
          <body name="box"><freejoint/><geom size=".1"/></body>
          <body name="marker" mocap="true"><geom size=".1" contype="0" conaffinity="0"/></body>
          <body name="arm"><joint name="hinge"/><geom type="capsule" size=".1 .5"/></body>
        </worldbody><actuator><position joint="hinge"/></actuator></mujoco>""")
    sim = CpuBackend(model, 2, nthread=1)
    rng = np.random.default_rng(0)
    for name in ("qpos", "qvel", "ctrl", "mocap_pos", "mocap_quat", "userdata"):
        field = sim.field(name)
        field[:] = torch.from_numpy(rng.normal(size=tuple(field.shape)))
    assert set(state_layout(model, STATE_SPEC)) >= {"qpos", "warmstart", "ctrl", "mocap_pos",
                                                    "mocap_quat", "userdata"}
    state = sim.get_state(STATE_SPEC)
    for env in range(2):
        data = sim.batch.get_data(env)
        expected = np.zeros(mujoco.mj_stateSize(model, STATE_SPEC))
        mujoco.mj_getState(model, data, expected, STATE_SPEC)
        np.testing.assert_array_equal(state[env].numpy(), expected)
    sim.set_state(torch.tensor([0]), state[1:], STATE_SPEC)
    np.testing.assert_array_equal(sim.get_state(STATE_SPEC)[0], state[1])


def test_reset_to_and_restore_reproduce_observations_with_contact():
    """Goal, mocap marker and fingertip contact forces come back exactly in other envs."""
    env = make_env("RelocateSphere", num_envs=2, seed=5, nthread=1)
    env.reset()
    model = env.scene.model
    adr = int(model.joint(env.task.objects["sphere"].free_joint).qposadr[0])
    env.sim.field("qpos")[:, adr:adr + 3] = env.view.fingertip_pos().mean(dim=1)
    power = torch.tensor(env.embodiment.poses["power"])
    keys, frames = env.episode_keys, []
    for t in range(25):
        action = (env.home_action + (power - env.home_action) * min(1.0, t / 10)).float()
        obs, *_ = env.step(action.repeat(2, 1))
        frames.append((env.sim_state().clone(), action, obs))
    assert any(o["contact"].abs().sum() > 0 for _, _, o in frames)
    assert env.view.goal is not None and not torch.equal(env.view.goal[0], env.view.goal[1])
    env.reset()  # other episodes everywhere; then replay env 1's episode in env 0
    env.reset_to([0], keys[[1]])
    for state, action, obs in frames:
        got = env.restore([0], state[[1]], action[None])
        assert set(got) == set(obs)
        for group, value in obs.items():
            torch.testing.assert_close(got[group][0], value[1], rtol=0, atol=0, msg=group)


def test_lerobot_loads_the_dataset_and_its_metadata(demos):
    root, kept, stats = demos
    meta = read_meta(root)
    dataset = LeRobotDataset(f"dexbench/{root.name}", root=root, video_backend="pyav")
    assert dataset.num_episodes == 3 == len(kept) and len(dataset) == stats["frames"]
    for index, ep in enumerate(sorted(kept, key=lambda e: e.key)):
        start = sum(e.length for e in sorted(kept, key=lambda e: e.key)[:index])
        for t in (0, ep.length - 1):
            frame = dataset[start + t]
            assert frame["episode_index"] == index and frame["frame_index"] == t
            np.testing.assert_array_equal(frame["observation.state"].numpy(),
                                          ep.obs["observation.state"][t])
            np.testing.assert_array_equal(frame["action"].numpy(), ep.actions[t])
        assert meta["episodes"][index]["key"] == list(ep.key)
    assert dataset[0]["task"] == PickCube.instruction
    assert meta["sim_state"]["spec"] == STATE_SPEC and meta["fps"] == 60
    assert set(meta["versions"]) >= {"dexbench", "mujoco", "lerobot", "torch"}
    assert len(meta["action_layout"]["actuators"]) == dataset.features["action"]["shape"][0]
    assert meta["env_config"]["task"] == "PickCube" and len(meta["config_hash"]) == 16
    assert meta["collection"]["expert"] == "CubeLifter" and meta["config"] == {"note": "test"}
    record = meta["episodes"][0]
    assert record["success"] and record["instruction"] == PickCube.instruction
    assert record["embodiment"] == "floating_shadow" and record["length"] >= 4
    # odd envs never lift: they time out, are counted and discarded
    assert stats["timeouts"] > 0 and stats["successes"] == 3
    assert stats["attempts"] == stats["successes"] + stats["timeouts"] + stats["failures"]
    assert json.loads((root / "collect_stats.json").read_text()) == stats
    # bytes per recorded step: at least the float64 simulator state
    assert stats["bytes_per_step"] > 0 and stats["raw_bytes_per_step"] >= 8 * 136
    assert not Staging(root).dir.exists()


def test_state_replay_reproduces_state_observations_exactly(demos, tmp_path):
    root, _, _ = demos
    out = tmp_path / "state"
    assert replay_states(root, out, "state", num_envs=3, progress=False, nthread=1) == []
    recorded, replayed = (read_episodes(r, read_meta(r)) for r in (root, out))
    assert [e.key for e in replayed] == [e.key for e in recorded]
    for a, b in zip(recorded, replayed, strict=True):
        assert sorted(a.obs) == sorted(b.obs) and "observation.contact" in b.obs
        for key in a.obs:
            np.testing.assert_array_equal(b.obs[key], a.obs[key], err_msg=key)
        np.testing.assert_array_equal(b.actions, a.actions)
    with pytest.raises(DatasetError, match="exists"):
        replay_states(root, out, "state", progress=False)


def test_rendering_restored_states_is_deterministic(demos, tmp_path):
    root, _, _ = demos
    meta = read_meta(root)
    episode = read_episodes(root, meta)[0]
    env = env_from_config(meta["env_config"], num_envs=1, obs="rgb_depth", history=0, **SMALL)
    env.reset_to([0], [episode.key])
    first = env.restore([0], episode.states[-1:])
    other = env.restore([0], episode.states[:1])
    again = env.restore([0], episode.states[-1:])
    for key in ("rgb/front", "depth/front"):
        assert torch.equal(first[key], again[key])
    assert not torch.equal(first["rgb/front"], other["rgb/front"])  # the cube moved
    out = tmp_path / "rgb"
    replay_states(root, out, "rgb_depth", num_envs=2, progress=False, **SMALL)
    data = LeRobotDataset("dexbench/rgb", root=out, video_backend="pyav",
                          depth_output_unit="m")
    frame = data[episode.length - 1]
    assert frame["observation.images.front"].shape == (3, 24, 32)
    np.testing.assert_array_equal((frame["observation.images.front"] * 255).round().byte()
                                  .permute(1, 2, 0).numpy(), first["rgb/front"][0].numpy())
    np.testing.assert_array_equal(frame["observation.depth.front"][0].numpy(),
                                  first["depth/front"][0].numpy())
    assert read_meta(out)["replay"]["history"] == 3
    assert read_meta(out)["replay"]["shadows"] is True


def test_resume_after_interruption_loses_and_repeats_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(PickCube, "lift_threshold", -1.0)  # success after the first step
    env = make_env("PickCube", num_envs=3, seed=0, nthread=1)
    out = tmp_path / "sway"
    settings = CollectSettings(num_demos=5, max_attempts=10, post_success_steps=2)
    before = []

    def interrupt_after_two(ep):
        before.append(ep)
        if len(before) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        collect(env, Sway(env), out, settings, {}, on_episode=interrupt_after_two,
                progress=False)
    staging = Staging(out)
    assert not out.exists() and len(list(staging.episodes.glob("*.npz"))) == 2
    (staging.episodes / "episode-0-0-9.npz.tmp").write_bytes(b"cut short by a kill")
    after = []
    capsys.readouterr()
    stats = collect(env, Sway(env), out, settings, {}, on_episode=after.append,
                    progress=False)
    assert f"resuming {staging.dir}: 2 kept of 2 attempts so far" in capsys.readouterr().err
    keys = [tuple(r["key"]) for r in read_meta(out)["episodes"]]
    assert len(keys) == len(set(keys)) == 5 and stats["successes"] == 5
    assert {e.key for e in before} | {e.key for e in after} == set(keys)
    assert not {e.key for e in before} & {e.key for e in after}
    stored = {e.key: e for e in read_episodes(out, read_meta(out))}
    for ep in before:
        np.testing.assert_array_equal(stored[ep.key].states, ep.states)
    assert not staging.dir.exists()
    # the same command again changes nothing; a larger num_demos extends
    assert collect(env, Sway(env), out, settings, {}, progress=False) == stats
    more = collect(env, Sway(env), out, CollectSettings(6, 10, 2), {}, progress=False)
    extended = [tuple(r["key"]) for r in read_meta(out)["episodes"]]
    assert more["successes"] == 6 and set(keys) < set(extended)
    with pytest.raises(DatasetError, match="other settings"):
        collect(env, Sway(env), out, CollectSettings(7, 10, 3), {}, progress=False)
    # actions alone reproduce these episodes exactly
    assert replay_main([f"dataset={out}", "mode=actions", "num_envs=3", "progress=false",
                        "sim.nthread=1"]) == 0
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert report["max_abs_qpos_error"] == 0.0 and report["successes"] == report["episodes"]


def test_action_replay_reports_divergence(demos, tmp_path, capsys):
    root, _, _ = demos
    assert replay_main([f"dataset={root}", "mode=actions", "progress=false",
                        "sim.nthread=1"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].split()[:3] == ["episode", "key", "frames"] and len(lines) == 1 + 3 + 1
    divergence = json.loads(pathlib.Path(json.loads(lines[-1])["divergence"]).read_text())
    # the cube was lifted by writing the state: actions alone do not lift it
    assert divergence["max_abs_qpos_error"] > 0.05 and divergence["successes"] == 0
    assert [r["recorded_success_step"] > 0 for r in divergence["episodes"]] == [True] * 3


def test_validate_catches_corruption_with_clear_messages(demos, tmp_path, capsys):
    root, _, _ = demos
    copy = tmp_path / "copy"
    shutil.copytree(root, copy)
    assert dexbench_main(["validate", f"dataset={copy}", "strict=true"]) == 0
    assert capsys.readouterr().out.splitlines()[0].endswith("ok")

    data = copy / "data/chunk-000/file-000.parquet"
    assert pq.ParquetFile(data).metadata.row_group(0).column(0).compression == "ZSTD"
    good = data.read_bytes()
    data.write_bytes(good[: len(good) // 2])
    report = validate_dataset(copy, check_code=False)
    assert not report.ok and "file-000.parquet is truncated or corrupt" in report.errors[0]
    data.write_bytes(good[:100] + bytes(200) + good[300:])  # zstd pages no longer decode
    assert "file-000.parquet is truncated or corrupt" in validate_dataset(
        copy, check_code=False).errors[0]
    data.write_bytes(good)
    stats = copy / "meta/stats.json"
    text = stats.read_text()
    stats.write_text(text.replace("1", "2", 1))  # still parses
    errors = validate_dataset(copy, check_code=False).errors
    assert "stats.json" in errors[0] and "differs from the checksum" in errors[0]
    stats.write_text(text)
    data.unlink()
    assert "file-000.parquet is missing" in validate_dataset(copy, check_code=False).errors[0]
    data.write_bytes(good)
    assert validate_dataset(copy, check_code=False).ok

    (copy / "meta/tasks.parquet").unlink()
    assert dexbench_main(["validate", f"dataset={copy}", "check_code=false"]) == 1
    assert "tasks.parquet is missing" in capsys.readouterr().out
    shutil.copy(root / "meta/tasks.parquet", copy / "meta/tasks.parquet")

    meta_file = copy / "meta/dexbench.json"
    meta = json.loads(meta_file.read_text())
    del meta["env_config"]["visual"]["camera_fov"]  # recorded before the setting existed
    meta["model_digest"], meta["config_hash"] = "0" * 64, "0" * 16
    meta["action_layout"]["high"] = [h - 1.0 for h in meta["action_layout"]["high"]]
    meta_file.write_text(json.dumps(meta))
    report = validate_dataset(copy, nthread=1)
    assert any("actions outside the actuator ranges" in e for e in report.errors)
    assert "recorded with other code: visual.camera_fov: (absent) -> True" in report.warnings
    assert any("compiled model differs" in w for w in report.warnings)
    (copy / "meta/info.json").write_text("{not json")
    assert "info.json is corrupt" in validate_dataset(copy, check_code=False).errors[0]
    shutil.rmtree(copy / "meta")
    assert "not a finished dexbench dataset" in validate_dataset(copy).errors[0]


def test_paper_protocol_plans_every_hand_on_the_default_mount():
    others = ("allegro", "leap", "sharpa", "inspire", "wuji")
    assert collect_cli.paper_plan(["PickCube", "BimanualLiftTray"], 50, 2) == [
        ("PickCube", "floating_shadow", 50),
        *[("PickCube", f"floating_{h}", 2) for h in others],
        ("BimanualLiftTray", "bimanual_floating_shadow", 50),
        *[("BimanualLiftTray", f"bimanual_floating_{h}", 2) for h in others]]
    assert collect_cli.paper_plan(["PickCube"], 5, 0) == [("PickCube", "floating_shadow", 5)]


def test_collect_command_protocol_writes_datasets_and_summary(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(PickCube, "lift_threshold", -1.0)
    monkeypatch.setattr(collect_cli, "same_mount_hands", lambda name: ["floating_allegro"])

    def shadow_only(env):
        if env.embodiment.name != "floating_shadow":
            raise ValueError(f"no expert for {env.embodiment.name}")
        return Sway(env)

    argv = ["protocol=paper", "tasks=[PickCube]", "num_demos=2", "num_envs=2",
            "post_success_steps=1", "name=cli", "progress=false", "sim.nthread=1"]
    assert collect_cli.main(argv, make_expert=shadow_only) == 1  # one hand was skipped
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert not summary["complete"] and summary["demos"] == 2
    assert summary["tasks"] == ["PickCube"] and len(summary["datasets"]) == 1
    assert summary["skipped"] == [{"task": "PickCube", "embodiment": "floating_allegro",
                                   "reason": "no expert for floating_allegro"}]
    root = tmp_path / "runs/datasets/PickCube/floating_shadow/cli"
    stats = json.loads((root / "collect_stats.json").read_text())
    assert stats["bytes_per_step"] > 0 and stats["dataset"] == str(root)
    assert json.loads(pathlib.Path(summary["summary"]).read_text())["datasets"] == [stats]
    with pytest.raises(ConfigError, match=r"replay\.py"):
        collect_cli.main(["obs=rgb"], make_expert=Sway)
