"""rl.py and eval.py log to W&B with the `wandb:` block train.py uses (conf/wandb/):
offline, into the run folder, without an account; read back from the run's own
`.wandb` file with wandb's record reader."""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys

import pytest

from dexbench.cli.config import load_config
from dexbench.cli.rl import train

pytest.importorskip("wandb")
ROOT = pathlib.Path(__file__).resolve().parents[1]


def _records(run_dir: pathlib.Path) -> tuple[list[dict], dict]:
    """(history rows, final summary) of the one offline W&B run under `run_dir`."""
    from wandb.proto import wandb_internal_pb2
    from wandb.sdk.internal import datastore

    (path,) = run_dir.glob("wandb/offline-run-*/run-*.wandb")
    store = datastore.DataStore()
    store.open_for_scan(str(path))
    history, summary = [], {}
    while (data := store.scan_data()) is not None:
        record = wandb_internal_pb2.Record()
        record.ParseFromString(data)
        kind = record.WhichOneof("record_type")
        if kind == "history":
            history.append({"/".join(i.nested_key) or i.key: json.loads(i.value_json)
                            for i in record.history.item})
        elif kind == "summary":
            summary.update({"/".join(i.nested_key) or i.key: json.loads(i.value_json)
                            for i in record.summary.update})
    return history, summary


@pytest.fixture(autouse=True)
def _offline(tmp_path, monkeypatch):
    monkeypatch.setenv("WANDB_MODE", "offline")
    monkeypatch.setenv("WANDB_SILENT", "true")
    monkeypatch.setenv("WANDB_ERROR_REPORTING", "false")  # no Sentry: nothing leaves here
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path))


def test_one_wandb_block_for_train_rl_and_eval():
    for command in ("train", "rl", "eval"):
        cfg = load_config(command, [])
        assert dict(cfg.wandb) == {"enabled": False, "mode": "offline", "project": "dexbench"}


def test_rl_logs_each_curve_point(tmp_path):
    result = train(["sim.backend=cpu", "num_envs=4", "sim.nthread=1", "rl.max_iterations=2",
                    "rl.chunk=1", "rl.network.hidden_dims=[16]", "wandb.enabled=true"])
    history, summary = _records(pathlib.Path(result["run_dir"]))
    curve = [row for row in history if "rl/env_steps" in row]
    assert [row["_step"] for row in curve] == [0, 1]
    assert [row["rl/env_steps"] for row in curve] == [32, 64]
    assert all({"rl/mean_reward", "rl/wall_s", "rl/episodes"} <= set(row) for row in curve)
    assert summary["iterations"] == 2 and summary["task"] == "PickCube"


def test_eval_logs_its_table_chart_videos_and_success(tmp_path):
    """`python eval.py` as a user runs it, in a process of its own: run inside the whole
    suite's process (after ~1,000 other tests) it once wrote no history row."""
    done = subprocess.run(
        [sys.executable, str(ROOT / "eval.py"), "task=PickCube", "policy=expert",
         "episodes=1", "horizon=5", "sim.nthread=1", "progress=false", "video.episodes=[0]",
         "video.width=64", "video.height=64", "wandb.enabled=true"],
        capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-2000:]
    (run_dir,) = (tmp_path / "eval" / "PickCube" / "expert").iterdir()
    history, summary = _records(run_dir)
    (row,) = history
    assert row["eval/results/_type"] == "table-file" and row["eval/results/nrows"] == 1
    assert row["eval/success_by_category/_type"] == "image-file"
    (video,) = [k for k in row if k.startswith("eval/videos/PickCube/") and k.endswith("_type")]
    assert row[video] == "video-file"
    assert summary["overall_success"] == json.loads(
        (run_dir / "results.json").read_text())["overall"]
    assert summary["episodes"] == 1 and "success/PickCube" in summary
    (media,) = run_dir.glob("wandb/offline-run-*/files/media")
    kinds = {p.relative_to(media).parts[0] for p in media.rglob("*") if p.is_file()}
    assert kinds == {"table", "images", "videos"}
