"""The closed-loop evaluator: Wilson intervals, tables and merges on synthetic results,
end-to-end runs with a trained DP and the scripted expert (kill/interrupt and resume
give the same final table), videos, missing tasks, and the eval throughput benchmark."""

import csv
import json
import pathlib
import subprocess
import sys
import time

import av
import pytest

from dexbench.cli import collect as collect_cli
from dexbench.cli import eval as eval_cli
from dexbench.cli import train as train_cli
from dexbench.cli.config import ConfigError, load_config
from dexbench.cli.eval import EvalError, check, evaluate, prepare
from dexbench.cli.merge import merge
from dexbench.eval.merge import MergeError, markdown, merge_runs, write_merged
from dexbench.eval.merge import latex as merged_latex
from dexbench.eval.metrics import summarize, wilson_interval
from dexbench.eval.plot import category_chart
from dexbench.eval.records import EpisodeLog, EpisodeRecord
from dexbench.eval.seeds import EVAL_ENV, eval_keys
from dexbench.eval.tables import write_tables
from dexbench.tasks.registry import TASKS as TASK_REGISTRY

REPO = pathlib.Path(__file__).resolve().parents[1]
TASKS = ("PickCube", "PushButton")
TINY_DP = ["policy.unet.channels=[8,16]", "policy.unet.step_embed_dim=8",
           "policy.encoder.hidden=16", "policy.encoder.out=8", "policy.optim.batch_size=16",
           "policy.noise.num_inference_steps=3"]


@pytest.mark.parametrize("k, n, low, high", [
    (0, 10, 0.0, 0.2775), (5, 10, 0.2366, 0.7634), (10, 10, 0.7225, 1.0),
    (0, 50, 0.0, 0.0713), (50, 50, 0.9287, 1.0), (25, 50, 0.3664, 0.6336),
])
def test_wilson_interval_known_values(k, n, low, high):
    got = wilson_interval(k, n)
    assert got == pytest.approx((low, high), abs=5e-5)


def test_wilson_interval_rejects_impossible_counts():
    for k, n in ((1, 0), (3, 2), (-1, 5)):
        with pytest.raises(ValueError):
            wilson_interval(k, n)


def _records(task: str, successes: list[bool]) -> list[EpisodeRecord]:
    return [EpisodeRecord(task, i, 0, s, 100 + i, 1.0, 0, "floating_shadow")
            for i, s in enumerate(successes)]


def _summary(policy: str, rates: dict[str, int], out: pathlib.Path) -> dict:
    groups = {"primitive": ["PickCube", "PushButton"], "articulation": ["OpenDrawer"]}
    records = [r for task, k in rates.items() for r in _records(task, [True] * k + [False] * (
        4 - k))]
    summary = summarize(groups, records, {"OpenDrawer": "no expert"}, {
        "label": "demo", "policy": policy, "policy_label": policy, "episodes_per_task": 4})
    out.mkdir(parents=True)
    write_tables(summary, out)
    return summary


def test_tables_chart_and_merge_on_synthetic_results(tmp_path):
    a = _summary("dp", {"PickCube": 3, "PushButton": 1}, tmp_path / "a")
    assert a["overall"] == pytest.approx(0.5)
    assert a["categories"] == [{"category": "primitive", "tasks": ["PickCube", "PushButton"],
                                "mean": pytest.approx(0.5)}]
    assert a["skipped"] == [{"task": "OpenDrawer", "reason": "no expert"}]
    md = (tmp_path / "a/results.md").read_text()
    assert "| primitive | PickCube | 0.75 | [0.30, 0.95] | 4 | 102 |" in md
    assert "skipped OpenDrawer: no expert" in md
    rows = list(csv.DictReader((tmp_path / "a/results.csv").open()))
    assert [r["task"] for r in rows] == ["PickCube", "PushButton", "mean", "mean"]
    assert float(rows[0]["ci_low"]) == pytest.approx(wilson_interval(3, 4)[0], abs=1e-4)
    assert r"\toprule" in (tmp_path / "a/results.tex").read_text()
    assert json.loads((tmp_path / "a/results.json").read_text())["overall"] == 0.5
    category_chart(a, tmp_path / "chart.png")
    assert (tmp_path / "chart.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    _summary("dp3", {"PickCube": 3, "PushButton": 2}, tmp_path / "b")
    _summary("expert", {"PickCube": 4}, tmp_path / "c")
    table = merge_runs([tmp_path / "a", tmp_path / "b", tmp_path / "c"])
    assert table.policies == ["dp", "dp3", "expert"]
    assert table.cells["PushButton"] == {"dp": 0.25, "dp3": 0.5, "expert": None}
    assert table.means["all"] == {"dp": 0.5, "dp3": 0.625, "expert": 1.0}
    md = markdown(table)
    assert ("| primitive | PickCube | 0.75 [0.30, 0.95] | 0.75 [0.30, 0.95] | "
            "**1.00** [0.51, 1.00] |") in md
    assert "| primitive | PushButton | 0.25 [0.05, 0.70] | **0.50** [0.15, 0.85] | - |" in md
    # means carry no interval; one over part of the row is marked and never the best
    assert "| **all** | **mean** | 0.50 | **0.62** | 1.00 (1/2) |" in md
    assert "covers only the k of the row's n tasks" in md
    assert table.mean_row("all") == {"dp": 0.5, "dp3": 0.625, "expert": None}
    tex = merged_latex(table)
    assert r"\multirow{2}{*}{primitive}" in tex and r"\textbf{0.50}" in tex
    paths = write_merged(table, tmp_path / "merged")
    assert sorted(paths) == ["csv", "md", "png", "tex"] and all(p.exists() for p in paths.values())
    assert paths["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert merge_runs([tmp_path]).policies == table.policies  # a folder of runs: all of them
    (tmp_path / "empty").mkdir()
    with pytest.raises(MergeError, match=r"no results\.json"):
        merge_runs([tmp_path / "empty"])
    assert merge([str(tmp_path / "a"), str(tmp_path / "b"), f"out={tmp_path / 'cli'}"]) == 0
    assert merge(["--help"]) == 0 and merge([]) == 2  # usage, nothing written
    rows = list(csv.reader((tmp_path / "cli/merged.csv").open()))
    assert rows[0] == ["category", "task", "dp", "dp3", "dp ci_low", "dp ci_high",
                       "dp3 ci_low", "dp3 ci_high"] and rows[-1][:2] == ["all", "mean"]
    assert float(rows[1][4]) == pytest.approx(wilson_interval(3, 4)[0], abs=1e-4)
    with pytest.raises(ConfigError, match="no results"):
        merge([str(tmp_path / "empty")])


def test_episode_log_drops_a_line_torn_by_a_kill(tmp_path):
    log = EpisodeLog(tmp_path / "episodes.jsonl")
    first, second = _records("PickCube", [True, False])
    log.append(first)
    log.append(first)  # a duplicate keeps the first record
    with open(log.path, "a") as f:
        f.write('{"task": "PickCube", "episo')
    assert log.load() == [first]
    log.append(second)
    assert log.load() == [first, second]


def test_eval_keys_never_meet_demonstration_keys():
    keys = eval_keys(7, range(3))
    assert keys.tolist() == [[7, EVAL_ENV, 0], [7, EVAL_ENV, 1], [7, EVAL_ENV, 2]]


@pytest.fixture(scope="module")
def checkpoints(tmp_path_factory) -> pathlib.Path:
    """runs/train/<task>/floating_shadow/dp/<run>/ for both tasks: tiny DPs trained for a
    few steps on two expert demonstrations each."""
    root = tmp_path_factory.mktemp("runs")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("DEXBENCH_RUNS_DIR", str(root))
        for task in TASKS:
            data = root / "datasets" / task
            assert collect_cli.main([f"task={task}", "num_demos=2", "num_envs=2",
                                     "post_success_steps=2", f"out={data}", "progress=false",
                                     "sim.nthread=1"]) == 0
            assert train_cli.main(["policy=dp", f"task={task}", f"dataset={data}",
                                   "train.max_steps=2", "device=cpu", "progress=false",
                                   *TINY_DP]) == 0
    return root / "train"


def _dp_args(checkpoints: pathlib.Path, name: str, num_envs: int) -> list[str]:
    return ["tasks=[PickCube,PushButton]", "policy=dp", f"checkpoint={checkpoints}",
            "episodes=2", f"num_envs={num_envs}", "horizon=40", "device=cpu",
            "sim.nthread=1", "progress=false", f"name={name}", *TINY_DP]


def _run(argv: list[str], on_episode=None) -> tuple[dict, pathlib.Path]:
    run, run_dir = prepare(argv)
    return evaluate(run.spec, run.plans, run.skipped, run_dir, on_episode), run_dir


def _plans(argv: list[str]):
    run = check(load_config("eval", argv), argv)
    return run.plans, run.skipped


def test_dp_eval_killed_and_resumed_gives_the_same_table(checkpoints, tmp_path):
    whole, whole_dir = _run(_dp_args(checkpoints, "whole", 2))
    assert whole["complete"] and [t["task"] for t in whole["tasks"]] == list(TASKS)
    assert [t["episodes"] for t in whole["tasks"]] == [2, 2]
    assert whole_dir.parent.parent.name == "PickCube+PushButton"
    assert (whole_dir / "success_by_category.png").exists()

    proc = subprocess.Popen([sys.executable, "eval.py", *_dp_args(checkpoints, "killed", 1)],
                            cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    log = whole_dir.parent / "killed" / "episodes.jsonl"
    deadline = time.monotonic() + 120
    while not (log.exists() and log.read_text().count("\n") >= 1):
        assert proc.poll() is None, proc.stderr.read().decode()
        assert time.monotonic() < deadline
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    finished = len(EpisodeLog(log).load())
    assert 1 <= finished < 4

    resumed, run_dir = _run([f"resume={log.parent}", "num_envs=2"])
    assert resumed["complete"]
    records = EpisodeLog(run_dir / "episodes.jsonl").load()
    assert sorted((r.task, r.episode) for r in records) == [(t, i) for t in TASKS
                                                            for i in range(2)]
    assert log.read_text().count("\n") == 4  # nothing ran twice
    assert (run_dir / "results.csv").read_text() == (whole_dir / "results.csv").read_text()


def test_expert_eval_interrupted_resumes_to_identical_episodes(tmp_path):
    args = ["task=PushButton", "policy=expert", "episodes=3", "sim.nthread=1",
            "progress=false", "video.episodes=[1]", "video.width=64", "video.height=48"]
    whole, whole_dir = _run([*args, "name=whole", "num_envs=3"])
    assert whole["tasks"][0]["success_rate"] == 1.0

    def stop_after_one(_record):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _run([*args, "name=cut", "num_envs=2"], on_episode=stop_after_one)
    cut_dir = whole_dir.parent / "cut"
    assert len(EpisodeLog(cut_dir / "episodes.jsonl").load()) == 1
    with pytest.raises(EvalError, match="other settings"):
        _run([*args, "name=cut", "episodes=4"])
    resumed, _ = _run([*args, "name=cut", "num_envs=2"])
    assert resumed["complete"]
    # Episode keys, not env slots, fix each episode: same steps on 3 envs or 2 after a stop.
    def outcomes(run: pathlib.Path) -> list[tuple]:
        return sorted((r.episode, r.success, r.steps)
                      for r in EpisodeLog(run / "episodes.jsonl").load())

    assert outcomes(cut_dir) == outcomes(whole_dir)
    assert (cut_dir / "results.csv").read_text() == (whole_dir / "results.csv").read_text()
    video = next((whole_dir / "videos" / "PushButton").glob("episode0001-*.mp4"))
    steps = next(json.loads(line)["steps"] for line in (whole_dir / "episodes.jsonl").open()
                 if json.loads(line)["episode"] == 1)
    with av.open(str(video)) as container:
        frames = list(container.decode(video=0))
    assert len(frames) == steps + 1 and frames[0].width == 64


def test_split_with_missing_tasks_fails_unless_skipped(monkeypatch):
    """A split listing tasks that are not implemented (all 100 are now: two are taken out
    of the registry here) fails, naming them, unless they are skipped."""
    split = load_config("eval", ["+split=all"]).split
    tasks = [str(t) for ts in split.categories.values() for t in ts]
    for name in ("NutThread", "CleanTable"):
        monkeypatch.delitem(TASK_REGISTRY, name)
    missing = [t for t in tasks if t not in TASK_REGISTRY]
    assert sorted(missing) == ["CleanTable", "NutThread"]
    with pytest.raises(EvalError) as err:
        _plans(["+split=all", "policy=expert"])
    message = str(err.value)
    assert f"{len(missing)} of the {len(tasks)} tasks of all" in message
    assert missing[0] in message and "+skip_missing=true" in message
    assert "PickCube" not in message
    plans, skipped = _plans(["+split=all", "policy=expert", "+skip_missing=true"])
    assert [p.task for p in plans] == [t for t in tasks if t in TASK_REGISTRY]
    assert sorted(skipped) == sorted(missing)


def test_wrong_arity_and_checkpoint_errors_are_clear(tmp_path):
    with pytest.raises(EvalError, match="needs two hands; embodiment floating_shadow has one"):
        _plans(["task=BimanualLiftTray", "embodiment=floating_shadow"])
    with pytest.raises(EvalError, match="takes no checkpoint"):
        _plans(["task=PickCube", f"checkpoint={tmp_path}"])


def test_bench_eval_reports_batched_and_sequential_throughput(tmp_path):
    result = eval_cli.bench_eval(["num_envs=3", "episodes=3", "sequential_episodes=1",
                                  "horizon=16", "sim.nthread=1", "progress=false",
                                  *TINY_DP])
    assert result["policy"] == "dp" and result["num_envs"] == 3
    assert result["batched_eps_per_min"] > 0 and result["sequential_eps_per_min"] > 0
    assert result["ratio"] == pytest.approx(  # each number is rounded to 2 decimals
        result["batched_eps_per_min"] / result["sequential_eps_per_min"], rel=0.01, abs=0.01)
    assert pathlib.Path(result["checkpoint"]).name == "untrained.pt"
