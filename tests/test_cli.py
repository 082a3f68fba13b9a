"""Command-line contracts: list, inspect, bench, and one-line errors."""

import json
import pathlib
import subprocess
import sys

import pytest
from test_tasks import TASK_KINDS

from dexbench.cli.bench import bench_render, bench_sim
from dexbench.cli.config import ConfigError, load_config
from dexbench.cli.introspect import entry, inspect
from dexbench.embodiments.builder import embodiment_names
from dexbench.tasks.registry import TASKS


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, timeout=300)


def _entry(monkeypatch, capsys, *args: str) -> tuple[int, str]:
    """`python -m dexbench <args>` in this process (the imports are paid once)."""
    monkeypatch.setattr(sys, "argv", ["dexbench", *args])
    with pytest.raises(SystemExit) as done:
        entry()
    return done.value.code, capsys.readouterr().out


def test_list_tasks_and_embodiments(monkeypatch, capsys):
    code, out = _entry(monkeypatch, capsys, "list", "tasks")
    assert code == 0
    rows = [line.split() for line in out.splitlines()]
    assert sorted(r[0] for r in rows) == sorted(TASKS) and len(rows) == len(TASKS)
    assert {r[0]: r[1] for r in rows}["PushT"] == "nonprehensile"
    code, out = _entry(monkeypatch, capsys, "list", "embodiments")
    names = [line.split()[0] for line in out.splitlines()]
    assert code == 0 and names == embodiment_names() and len(names) == 48


def test_inspect_prints_one_json_object():
    out = _run("-m", "dexbench", "inspect", "task=PickCube", "embodiment=fr3_allegro")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["action_dim"] == len(info["actuators"]) == 7 + 16
    assert info["obs"]["proprio"] == [23] and info["obs"]["state"] == [7]
    assert info["control_dt"] == pytest.approx(1 / 60)
    assert info["episode_steps"] == 1200


@pytest.mark.parametrize("task", TASK_KINDS)
def test_inspect_works_for_every_task(task):
    info = json.loads(inspect([f"task={task}"]))
    assert info["task"] == task and info["action_dim"] == len(info["actuators"])
    assert info["episode_steps"] == round(TASKS[task].episode_seconds * 60)
    assert "state" in info["obs"] and "privileged" not in info["obs"]


@pytest.mark.parametrize("arg, needle", [
    ("task=Nope", "unknown task 'Nope'"),
    ("embodiment=floating_claw", "unknown embodiment"),
    ("nosuchkey=1", "nosuchkey"),
    ("camera.cloud_device=tpu", "use null, cpu or cuda"),
])
def test_bad_input_gives_one_line_error(arg, needle):
    out = _run("-m", "dexbench", "inspect", arg)
    assert out.returncode == 2
    assert needle in out.stderr and "Traceback" not in out.stderr
    assert out.stderr.strip().count("\n") == 0


def test_config_rejects_positional_arguments():
    with pytest.raises(ConfigError, match="key=value"):
        load_config("config", ["PickCube"])


def test_bench_sim_reports_throughput_and_writes_run_dir():
    result = bench_sim(["num_envs=4", "steps=5", "warmup=1"])
    for key in ("env_steps_per_s", "raw_physics_steps_per_s", "decimation", "ratio"):
        assert result[key] > 0
    assert result["decimation"] == 4
    run_dir = pathlib.Path(result["run_dir"])
    assert json.loads((run_dir / "metrics.json").read_text())["ratio"] == result["ratio"]
    assert (run_dir / "config.yaml").exists()


def test_bench_sim_on_warp_times_env_raw_and_camera_with_and_without_shadows():
    """The GPU benchmark's code path, on warp's CPU device (tiny sizes)."""
    from dexbench.cli.bench import format_table

    result = bench_sim(["sim.backend=warp", "num_envs=2", "steps=3", "warmup=1",
                        "camera_envs=2", "width=16", "height=16"])
    for key in ("env_steps_per_s", "raw_physics_steps_per_s", "ratio",
                "env_steps_per_s_without_contact", "camera_env_steps_per_s",
                "camera_no_shadows_env_steps_per_s"):
        assert result[key] > 0, key
    assert result["sim_warnings"] == 0
    table = format_table(result)
    assert "without shadows" in table and "ratio env/raw" in table


def test_bench_render_reports_images_per_second():
    result = bench_render(["num_envs=2", "steps=2", "width=32", "height=32",
                           "renderers=[cpu,warp]"])
    assert [r["renderer"].split()[0] for r in result["results"]] == ["cpu", "warp"]
    assert all(r["images_per_s"] > 0 for r in result["results"])
    assert result["resolution"] == [32, 32] and result["num_envs"] == 2
    assert result["renderer"].startswith("cpu")  # the headline is the first result


def test_bench_train_times_the_training_loop_and_writes_run_dir():
    """A tiny DP on synthetic frames shaped like PickCube's state observations."""
    from dexbench.cli.bench_train import BENCH_TRAIN, bench_train_in

    cfg = load_config("bench_train", ["policy=dp", "policy.unet.channels=[8,16,32]",
                                      "policy.optim.batch_size=8", "frames=512", "steps=3",
                                      "warmup=1", "device=cpu"])
    result = bench_train_in(cfg, BENCH_TRAIN.folder(cfg, "t"))
    assert result["steps_per_s_total"] > 0 and result["steps_per_s_each"] == [
        result["steps_per_s_total"]]
    assert result["device"] == "cpu" and result["batch_size"] == 8
    run_dir = pathlib.Path(result["run_dir"])
    assert json.loads((run_dir / "metrics.json").read_text())["jobs"] == 1


def test_bench_train_rejects_no_jobs_in_one_line():
    out = _run("bench.py", "train", "jobs=0")
    assert out.returncode == 2 and "jobs >= 1" in out.stderr
    assert out.stderr.strip().count("\n") == 0


def test_bench_explore_counts_what_a_fresh_policy_reaches():
    """Two 0.1 s training episodes per env of PickCube with the initial policy's noise."""
    from dexbench.cli.bench_explore import BENCH_EXPLORE, explore_in

    cfg = load_config("bench_explore", ["num_envs=3", "episodes=2", "sim.nthread=1",
                                        "rl.episode_seconds=0.1"])
    result = explore_in(cfg, BENCH_EXPLORE.folder(cfg, "t"))
    assert result["env_steps"] == 3 * 2 * 6 and result["reset_episodes"] == 6
    assert 0 <= result["held_lifted_step_share"] <= result["ever_held_env_share"] + 1e-9 <= 1
    assert result["reset_success_rate"] == 0.0 and result["demo_starts"] is None
    assert 0 <= result["max_lift_mean_m"] <= result["max_lift_max_m"] < 0.1
    out = _run("bench.py", "explore", "episodes=0")
    assert out.returncode == 2 and "episodes=0" in out.stderr
    assert out.stderr.strip().count("\n") == 0


def test_snapshot_writes_a_labelled_contact_sheet():
    import numpy as np
    from PIL import Image

    from dexbench.cli.snapshot import (
        GAP_PX,
        HEADER_PX,
        ROW_LABEL_PX,
        column_labels,
        snapshot,
    )

    path = pathlib.Path(snapshot(["task=PickCube", "visual=train", "num_envs=2",
                                  "camera.width=40", "camera.height=30"]))
    image = np.asarray(Image.open(path).convert("L"))
    # 3 views + wrist + depth + cloud, 2 envs, under a header and beside row labels
    assert image.shape == (HEADER_PX + 2 * 30 + GAP_PX, ROW_LABEL_PX + 6 * 40 + 5 * GAP_PX)
    header, row_labels = image[:HEADER_PX, ROW_LABEL_PX:], image[HEADER_PX:, :ROW_LABEL_PX]
    assert (header < 128).any() and (row_labels < 128).any()  # text drawn in both
    labels = column_labels(["front", "left", "right", "right/hand/wrist_cam"])
    assert [m for m, _ in labels] == ["rgb"] * 4 + ["depth", "point cloud"]
    assert labels[3][1] == "right wrist" and labels[4][1].startswith("front")
