"""DP and DP3: train a few steps on real expert demos, save, reload, act on a batched env;
normalizer, chunking, windows and checkpoint resolution; the errors users meet."""

import json
import pathlib

import numpy as np
import pytest
import torch

from dexbench.cli import train as train_cli
from dexbench.cli.config import ConfigError
from dexbench.data.meta import DatasetError
from dexbench.policies.common.checkpoint import (
    CheckpointError,
    load_checkpoint,
    resolve_checkpoint,
)
from dexbench.policies.common.chunking import ChunkedActor
from dexbench.policies.common.demos import Demos, load_demos, windows
from dexbench.policies.common.normalizer import MinMaxNormalizer
from dexbench.policies.common.protocol import ActionLayoutError
from dexbench.policies.registry import policy_module
from dexbench.tasks.registry import make_env

CAMERA = {"image_size": (32, 24), "num_points": 64}
COMMON = ["train.max_steps=3", "device=cpu", "progress=false", "sim.nthread=1",
          "policy.unet.channels=[8,16]", "policy.unet.step_embed_dim=8",
          "policy.optim.batch_size=16", "policy.noise.num_inference_steps=3"]
TINY = {
    "dp": ["policy.encoder.hidden=16", "policy.encoder.out=8"],
    "dp3": ["policy.encoder.point_hidden=[8,16]", "policy.encoder.point_out=8",
            "policy.encoder.state_out=8", "camera.width=32", "camera.height=24",
            "camera.num_points=64", "num_envs=4"],
}


@pytest.fixture(scope="module")
def trained(pickcube_demos, tmp_path_factory) -> dict[str, pathlib.Path]:
    """A run folder per policy kind, trained for a few steps with tiny networks."""
    root = tmp_path_factory.mktemp("runs")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("DEXBENCH_RUNS_DIR", str(root))
        for kind in ("dp", "dp3"):
            assert train_cli.main([f"policy={kind}", f"dataset={pickcube_demos}", *COMMON,
                                   *TINY[kind]]) == 0
    return {kind: next(root.glob(f"train/PickCube/floating_shadow/{kind}/*"))
            for kind in ("dp", "dp3")}


def _rollout(kind: str, checkpoint: pathlib.Path, steps: int,
             lazy: bool = False) -> list[torch.Tensor]:
    """Actions of `steps` control steps; `lazy`: camera groups rendered only for the envs
    whose next frame the policy says it reads."""
    module = policy_module(kind)
    spec = module.spec(checkpoint, {})
    env = make_env(spec.task, spec.embodiment, num_envs=3, seed=11, obs=spec.obs, nthread=1,
                   history=0 if lazy else None, **(CAMERA if kind == "dp3" else {}))
    policy = module.build(checkpoint, env, "cpu", {})
    obs = env.reset()
    policy.reset(torch.arange(3))
    actions, skipped = [], 0
    for t in range(steps):
        action = policy.act(obs)
        assert action.shape == (3, env.action_dim) and torch.isfinite(action).all()
        actions.append(action)
        observe = policy.reads_next() if lazy else None
        obs, *_ = env.step(action, observe=observe)
        if observe is not None:
            skipped += int((~observe).sum())
            assert (obs["pointcloud"][~observe] == 0).all()  # not rendered
        if t == 4:  # env 1 starts over: only its history and queue restart
            obs = env.reset([1])
            policy.reset(torch.tensor([1]))
    assert skipped > 0 or not lazy
    return actions


@pytest.mark.parametrize("kind", ["dp", "dp3"])
def test_train_save_reload_and_act(trained, kind):
    run = trained[kind]
    summary = json.loads((run / "summary.json").read_text())
    assert summary["steps"] == 3 and summary["stop_reason"] == "max_steps"
    assert len(summary["val_episodes"]) == 1 and len(summary["train_episodes"]) == 2
    header = (run / "metrics.csv").read_text().splitlines()[0]
    assert header.startswith("epoch,step,train_loss,val_loss")
    assert resolve_checkpoint(run) == run / "best.pt" and (run / "last.pt").is_file()
    payload = load_checkpoint(run, kind)
    assert payload["obs"] == ("state" if kind == "dp" else "pointcloud")
    assert payload["task"] == "PickCube" and payload["embodiment"] == "floating_shadow"
    assert payload["config"]["policy"]["name"] == kind and payload["step"] == 3
    assert set(payload["normalizer"]["low"]) == {"action", *payload["groups"]}
    first, again = _rollout(kind, run, 10), _rollout(kind, run, 10)
    for a, b in zip(first, again, strict=True):
        torch.testing.assert_close(a, b, rtol=0, atol=0)
    # actions stay inside the range the demonstrations span (normalizer + clipped samples)
    low, high = (payload["normalizer"][k]["action"] for k in ("low", "high"))
    assert all(((a >= low - 1e-4) & (a <= high + 1e-4)).all() for a in first)


def test_dp3_rendering_only_the_frames_it_reads_gives_the_same_actions(trained):
    eager, lazy = (_rollout("dp3", trained["dp3"], 12, lazy=flag) for flag in (False, True))
    for a, b in zip(eager, lazy, strict=True):
        torch.testing.assert_close(a, b, rtol=0, atol=0)


def test_dp3_replays_point_clouds_once_beside_the_dataset(trained, pickcube_demos):
    replayed = pickcube_demos.with_name(f"{pickcube_demos.name}-pointcloud")
    cloud = load_demos(replayed, ["pointcloud"]).obs["pointcloud"]
    assert cloud.shape[1:] == (64, 3) and np.isfinite(cloud).all()
    payload = load_checkpoint(trained["dp3"], "dp3")
    assert payload["dataset"] == str(replayed) and payload["groups"] == ["pointcloud", "proprio"]


def test_checkpoint_refuses_another_embodiment(trained):
    env = make_env("PickCube", "floating_allegro", num_envs=1, nthread=1)
    with pytest.raises(ActionLayoutError, match=r"embodiment 'floating_shadow'.*"
                       r"embodiment=floating_shadow or retrain"):
        policy_module("dp").build(trained["dp"], env, "cpu", {})
    with pytest.raises(CheckpointError, match="pass policy=dp"):
        policy_module("dp3").spec(trained["dp"], {})


def test_missing_dataset_names_the_collect_command(tmp_path):
    with pytest.raises(DatasetError, match=r"python collect\.py task=PickCube "
                       r"embodiment=floating_shadow"):
        train_cli.main(["policy=dp", "task=PickCube", *COMMON])


def test_normalizer_round_trip():
    rng = np.random.default_rng(0)
    data = {"action": rng.normal(size=(50, 4)) * [1, 10, 0.1, 0],
            "pointcloud": rng.uniform(-2, 3, size=(5, 7, 3))}
    norm = MinMaxNormalizer.fit({k: torch.as_tensor(v) for k, v in data.items()})
    again = MinMaxNormalizer.from_state_dict(norm.state_dict())
    for key, value in data.items():
        x = torch.as_tensor(value, dtype=torch.float32)
        y = again.normalize(key, x)
        assert y.min() >= -1 - 1e-6 and y.max() <= 1 + 1e-6
        torch.testing.assert_close(again.unnormalize(key, y), x, rtol=1e-5, atol=1e-5)
    assert (norm.normalize("action", torch.zeros(2, 4))[:, 3] == 0).all()  # constant: 0
    assert (norm.unnormalize("action", torch.ones(2, 4))[:, 3] == 0).all()  # and back


def test_chunked_actor_plans_only_for_envs_whose_queue_ran_out():
    calls = []

    def plan(windows):
        calls.append(windows["x"].shape[0])
        return windows["x"][:, -1:, :1].repeat(1, 4, 2) + torch.arange(4.0)[None, :, None]

    actor = ChunkedActor(num_envs=2, n_obs_steps=2, n_action_steps=3, action_dim=2)
    out = [actor.act({"x": torch.full((2, 1), float(t))}, plan) for t in range(3)]
    assert calls == [2] and [o[0, 0].item() for o in out] == [0.0, 1.0, 2.0]
    actor.reset(torch.tensor([1]))
    actor.act({"x": torch.full((2, 1), 10.0)}, plan)
    assert calls == [2, 2]  # env 0's queue ran out too
    actor.act({"x": torch.full((2, 1), 11.0)}, plan)
    actor.reset(torch.tensor([0]))
    actor.act({"x": torch.full((2, 1), 12.0)}, plan)
    assert calls == [2, 2, 1]
    assert torch.equal(actor.window.history["x"][0, :, 0], torch.tensor([12.0, 12.0]))  # refilled
    assert torch.equal(actor.window.history["x"][1, :, 0], torch.tensor([11.0, 12.0]))


def test_chunked_actor_reads_only_the_frames_its_next_plan_sees():
    """n_obs_steps=2, n_action_steps=4: after the plan at call 0, calls 3 and 4 feed the
    window of the plan at call 4; calls 1 and 2 are pushed out unread."""
    actor = ChunkedActor(num_envs=1, n_obs_steps=2, n_action_steps=4, action_dim=1)
    seen = []

    def plan(windows):
        seen.append(windows["x"][0, :, 0].tolist())
        return torch.zeros(1, 4, 1)

    reads = []
    for t in range(9):
        read = actor.reads_next()[0].item() if t else True  # call 0: the reset's frame
        reads.append(read)
        actor.act({"x": torch.tensor([[float(t) if read else -1.0]])}, plan)
    assert reads == [True, False, False, True, True, False, False, True, True]
    assert seen == [[0.0, 0.0], [3.0, 4.0], [7.0, 8.0]]  # never an unread frame
    wide = ChunkedActor(num_envs=3, n_obs_steps=5, n_action_steps=2, action_dim=1)
    assert wide.reads_next().all()  # a window longer than a chunk reads every frame


def test_windows_repeat_the_first_observation_and_the_last_action():
    obs, act = windows(np.array([3, 5]), n_obs_steps=2, horizon=4)
    assert obs.tolist() == [[0, 0], [0, 1], [1, 2], [3, 3], [3, 4]]
    assert act.tolist() == [[0, 1, 2, 2], [1, 2, 2, 2], [2, 2, 2, 2], [3, 4, 4, 4], [4, 4, 4, 4]]


def test_checkpoint_paths_resolve_to_best_then_last_then_newest_run(tmp_path):
    old, new = tmp_path / "20260101-a", tmp_path / "20260102-b"
    for run in (old, new):
        run.mkdir()
        (run / "last.pt").write_bytes(b"")
    assert resolve_checkpoint(tmp_path) == new / "last.pt"
    (new / "best.pt").write_bytes(b"")
    assert resolve_checkpoint(new) == new / "best.pt"
    with pytest.raises(CheckpointError, match="train one"):
        resolve_checkpoint(tmp_path / "missing")
    with pytest.raises(CheckpointError, match="not a readable checkpoint"):
        load_checkpoint(new, "dp")


def test_demos_round_trip_through_a_compact_file(pickcube_demos, tmp_path):
    loaded = load_demos(pickcube_demos, ["proprio", "state"])
    loaded.save(tmp_path / "demos.npz")
    back = Demos.load(tmp_path / "demos.npz")
    assert back.meta == loaded.meta and back.episode_ends.tolist() == \
        loaded.episode_ends.tolist()
    np.testing.assert_array_equal(back.obs["proprio"], loaded.obs["proprio"])
    np.testing.assert_array_equal(back.actions, loaded.actions)


def test_policy_groups_choose_the_inputs(pickcube_demos, tmp_path, monkeypatch):
    """`policy.groups` trains on some of the groups only (here without `policy`, the
    previous action); the checkpoint records them and acts on an env that has them all.
    A group the policy cannot use is one clear error."""
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path))
    assert train_cli.main(["policy=dp", f"dataset={pickcube_demos}", *COMMON, *TINY["dp"],
                           "policy.groups=[proprio,state]"]) == 0
    run = next(tmp_path.glob("train/PickCube/floating_shadow/dp/*"))
    assert load_checkpoint(run, "dp")["groups"] == ["proprio", "state"]
    assert len(_rollout("dp", run, 3)) == 3
    with pytest.raises(ConfigError, match=r"\['pointcloud'\] not among this policy's inputs"):
        train_cli.main(["policy=dp", f"dataset={pickcube_demos}", *COMMON, *TINY["dp"],
                        "policy.groups=[proprio,pointcloud]"])
