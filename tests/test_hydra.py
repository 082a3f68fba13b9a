"""Hydra as designed: `--help` with the config groups, one-line errors for wrong
overrides, typed configs as the one source of defaults, sweeps on the joblib and submitit
launchers (for real, on CPU), a split swept task by task and merged into one table,
`train.py -m` over two policies, the package list that installs conf/, and closed-loop
evaluation on the warp backend (warp's CPU device) against the CPU backend's files.

Ray's launcher is not run here: it is an optional extra (about 400 MB, and its
`cloudpickle<3` pin conflicts with joblib 1.6).
"""

from __future__ import annotations

import csv
import json
import pathlib
import runpy
import sys
import tomllib
from dataclasses import replace

import pytest

from dexbench.cli import train as train_cli
from dexbench.cli.config import ConfigError, env_kwargs, load_config, spread_device
from dexbench.cli.eval import EvalError, evaluate, prepare
from dexbench.cli.introspect import main as dexbench_main
from dexbench.data.collect import CollectSettings, collect
from dexbench.envs.arena import PhysicsOptions
from dexbench.envs.variation import PhysicalVariation, VisualVariation
from dexbench.eval.records import EpisodeLog
from dexbench.experts import make_expert
from dexbench.tasks.registry import TASKS, make_env

ROOT = pathlib.Path(__file__).resolve().parents[1]
TINY_EVAL = ["policy=expert", "episodes=1", "horizon=5", "sim.nthread=1", "progress=false"]


def _run(capsys, script: str, *args: str) -> tuple[int, str, str]:
    """(exit status, stdout, stderr) of `python <script> <args>`, run in this process as
    its `__main__` (the imports are paid once; launchers still start their own)."""
    mp = pytest.MonkeyPatch()
    mp.setattr(sys, "argv", [script, *args])
    capsys.readouterr()
    try:
        with pytest.raises(SystemExit) as stop:
            runpy.run_path(str(ROOT / script), run_name="__main__")
    finally:
        mp.undo()
    out, err = capsys.readouterr()
    return stop.value.code, out, err


def _results(root: pathlib.Path) -> list[dict]:
    return [json.loads(p.read_text()) for p in sorted(root.rglob("results.json"))]


def test_help_lists_the_config_groups(capsys):
    code, out, err = _run(capsys, "train.py", "--help")
    assert code == 0, err
    assert "== Configuration groups ==" in out
    section = out.split("== Configuration groups ==")[1].split("== Config ==")[0]
    groups = dict(line.split(": ", 1) for line in section.splitlines() if ": " in line)
    assert {"dp", "dp3", "expert"} <= set(groups["policy"].split(", "))
    assert "baseline19" in groups["split"] and "randomized" in groups["physical"]


@pytest.mark.parametrize("args, needle", [
    (["train.py", "nokey=1"], "nokey"),
    (["eval.py", "-m", "task=PickCube,PushButton", "nokey=1"], "nokey"),
    (["eval.py", "visual.enabled=maybe"], "visual.enabled"),
    (["eval.py", "-m", "task=PickCube,Nope", "policy=expert"], "job task=Nope"),
])
def test_a_wrong_override_is_one_line_and_writes_nothing(args, needle, tmp_path, capsys):
    code, _, err = _run(capsys, *args)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith("error: ") and needle in lines[0]
    assert not (tmp_path / "runs").exists()


def test_typed_configs_hold_the_defaults():
    kwargs = env_kwargs(load_config("config", ["visual=test", "physical=randomized",
                                               "sim.integrator=euler"]))
    assert kwargs["visual"] == replace(VisualVariation(), enabled=True, split="test")
    assert kwargs["physical"] == replace(PhysicalVariation(), enabled=True, obs_noise=0.005)
    assert kwargs["physics"] == replace(PhysicsOptions(), integrator="euler")
    # the YAML sets only what differs from the dataclasses' defaults
    assert "materials" not in (ROOT / "conf/visual/train.yaml").read_text()
    assert "timestep:" not in (ROOT / "conf/config.yaml").read_text()
    with pytest.raises(ConfigError, match=r"visual\.enabled"):
        load_config("eval", ["visual.enabled=maybe"])


def test_split_swept_task_by_task_on_joblib_and_merged(tmp_path, capsys):
    assert dexbench_main(["split", "baseline19"]) == 0
    tasks = capsys.readouterr().out.strip().split(",")
    assert {"OpenFaucet", "PushT"} <= set(tasks) <= set(TASKS)
    code, out, err = _run(capsys, "eval.py", "-m", "+split=baseline19",
                          "split_task=OpenFaucet,PushT", *TINY_EVAL, "hydra/launcher=joblib")
    assert code == 0, err
    assert "Joblib.Parallel(n_jobs=-1" in out + err
    (sweep,) = (tmp_path / "runs/eval/multirun").iterdir()
    runs = _results(sweep)
    assert sorted(r["tasks"][0]["task"] for r in runs) == ["OpenFaucet", "PushT"]
    assert all((pathlib.Path(r["run_dir"]) / ".hydra/overrides.yaml").exists() for r in runs)
    assert dexbench_main(["merge", str(sweep), f"out={tmp_path / 'merged'}"]) == 0
    rows = list(csv.reader((tmp_path / "merged/merged.csv").open()))
    assert rows[0][:3] == ["category", "task", "expert"]  # one column: the jobs' tasks differ
    assert rows[0][3:] == ["expert ci_low", "expert ci_high"]
    assert {r[1] for r in rows} >= {"OpenFaucet", "PushT"}


def test_submitit_local_launcher_runs_each_job(tmp_path, capsys):
    code, _, err = _run(capsys, "eval.py", "-m", "task=PickCube,PushButton", *TINY_EVAL,
                        "hydra/launcher=submitit_local", "hydra.launcher.timeout_min=5")
    assert code == 0, err
    runs = _results(tmp_path / "runs/eval/multirun")
    assert sorted(r["tasks"][0]["task"] for r in runs) == ["PickCube", "PushButton"]
    assert list((tmp_path / "runs/eval/multirun").rglob(".submitit"))


def test_train_sweep_trains_dp_and_dp3(tmp_path, capsys):
    """`python train.py -m policy=dp,dp3 task=PickCube train.max_steps=... device=cpu`
    on the demonstrations where collect.py puts them by default."""
    env = make_env("PickCube", num_envs=2, seed=3, nthread=1)
    data = tmp_path / "runs/datasets/PickCube/floating_shadow/seed0"
    stats = collect(env, make_expert(env), data, CollectSettings(2, 6, post_success_steps=2),
                    {}, progress=False)
    assert stats["successes"] == 2
    code, _, err = _run(capsys, "train.py", "-m", "policy=dp,dp3", "task=PickCube",
                        "train.max_steps=2", "device=cpu", "progress=false", "sim.nthread=1",
                        "num_envs=2", "policy.unet.channels=[8,16]",
                        "policy.unet.step_embed_dim=8", "policy.optim.batch_size=16",
                        "camera.width=32", "camera.height=24", "camera.num_points=64")
    assert code == 0, err
    sweep = tmp_path / "runs/train/multirun"
    for kind in ("dp", "dp3"):
        (best,) = sweep.glob(f"*/PickCube/floating_shadow/{kind}/*/best.pt")
        assert (best.parent / "summary.json").exists()
    # the sweep's up-front test of every job reads the dataset's metadata only: loading
    # (and DP3's replay) is left to the jobs, which run in parallel on a launcher
    mp = pytest.MonkeyPatch()
    mp.setattr(train_cli, "training_data", lambda *a: pytest.fail("loaded in validate"))
    try:
        cfg = load_config("train", ["policy=dp3", "task=PickCube", "device=cpu"])
        assert train_cli.COMMAND.validate(cfg, [])[0].OBS == "pointcloud"
        with pytest.raises(ConfigError, match="holds PickCube on floating_shadow"):
            train_cli.COMMAND.validate(load_config("train", [
                "policy=dp", "task=PushT", f"dataset={data}"]), [])
    finally:
        mp.undo()


def test_device_auto_spreads_sweep_jobs_over_the_gpus():
    """`device=auto` in job k of a `-m` sweep on a machine with several GPUs: cuda:(k mod
    GPUs); with one GPU, outside a sweep, or named explicitly: as given."""
    assert [spread_device("auto", k, 4) for k in range(6)] == [
        "cuda:0", "cuda:1", "cuda:2", "cuda:3", "cuda:0", "cuda:1"]
    assert spread_device("auto", 3, 1) == "auto"
    assert spread_device("auto", None, 4) == "auto"
    assert spread_device("cuda:2", 5, 4) == "cuda:2"


def test_pyproject_installs_every_package_and_conf():
    setup = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    code = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "dexbench").rglob("*.py")}
    conf = {".".join(("dexbench", *p.parent.relative_to(ROOT).parts))
            for p in (ROOT / "conf").rglob("*.yaml")}
    assert set(setup["packages"]) == code | conf
    assert setup["package-dir"] == {"dexbench.conf": "conf"}


def _eval(argv: list[str]) -> tuple[dict, pathlib.Path]:
    run, run_dir = prepare(argv)
    return evaluate(run.spec, run.plans, run.skipped, run_dir), run_dir


def test_warp_backend_eval_writes_what_the_cpu_backend_writes(tmp_path):
    args = ["task=PickCube", "policy=expert", "episodes=2", "horizon=5", "sim.nthread=1",
            "progress=false"]
    cpu, cpu_dir = _eval([*args, "name=cpu"])
    warp, warp_dir = _eval([*args, "sim.backend=warp", "name=warp"])
    assert warp["complete"] and warp["backend"] == "warp" and cpu["backend"] == "cpu"
    assert sorted(p.name for p in warp_dir.iterdir()) == sorted(p.name for p in cpu_dir.iterdir())

    def keys(run: pathlib.Path) -> list[tuple]:
        return sorted((r.task, r.episode, r.seed, r.steps)
                      for r in EpisodeLog(run / "episodes.jsonl").load())

    assert keys(warp_dir) == keys(cpu_dir)
    assert warp.keys() == cpu.keys() and warp["tasks"][0].keys() == cpu["tasks"][0].keys()
    assert "2 episodes on 2 envs" in (warp_dir / "eval.log").read_text()  # one world each
    with pytest.raises(EvalError, match=r"other settings \(sim\)"):
        prepare([*args, "name=warp"])  # a run keeps its backend
    with pytest.raises(EvalError, match="only num_envs"):
        prepare([f"resume={warp_dir}", "sim.backend=cpu"])
    # cameras, and so point clouds, through the warp renderer
    assert env_kwargs(load_config("config", ["sim.backend=warp"]))["renderer"] == "warp"
