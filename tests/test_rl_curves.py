"""`python -m dexbench curves`: several RL runs on one plot, with the table the docs quote
(pooled training success at given minutes, first minute at a target, evaluator result)."""

from __future__ import annotations

import json
import pathlib

import pytest
import yaml

from dexbench.cli.config import ConfigError
from dexbench.cli.curves import curves
from dexbench.rl.curve import SMOOTH, milestones, pooled


def _points(rates: list[float], episodes: int = 10, step_s: float = 30.0) -> list[dict]:
    return [{"iteration": i, "wall_s": step_s * (i + 1), "env_steps": 1000 * (i + 1),
             "episodes": episodes, "success_rate": r, "mean_reward": 0.0}
            for i, r in enumerate(rates)]


def _run(folder: pathlib.Path, seed: int, rates: list[float], algo: str = "ppo") -> pathlib.Path:
    folder.mkdir(parents=True)
    (folder / "curve.jsonl").write_text("".join(json.dumps(p) + "\n" for p in _points(rates)))
    (folder / "policy.json").write_text(json.dumps({"task": "PickCube", "algo": algo}))
    (folder / "config.yaml").write_text(yaml.safe_dump({"seed": seed}))
    return folder


def _evaluation(folder: pathlib.Path, task: str, rate: float) -> pathlib.Path:
    folder.mkdir(parents=True)
    (folder / "results.json").write_text(json.dumps({"tasks": [
        {"task": task, "success_rate": rate, "ci_low": rate - 0.1, "ci_high": rate + 0.05}]}))
    return folder


def test_success_is_pooled_over_the_last_iterations_episodes():
    points = _points([0.0] * (SMOOTH - 1) + [1.0])
    points[0]["episodes"] = 0  # an iteration that finished nothing does not count
    xs, ys = pooled(points)
    assert len(xs) == SMOOTH - 1 and xs[0] == pytest.approx(1.0)
    assert ys[-1] == pytest.approx(1 / (SMOOTH - 1))


def test_milestones_read_the_pooled_curve_at_minutes_and_the_first_target():
    # 30 s per iteration: minute 1 is iteration 1; success jumps to 1.0 from iteration 20
    points = _points([0.0] * 20 + [1.0] * 20)
    marks = milestones(points, (5.0, 20.0, 60.0), 0.8)
    assert marks["at"][5.0] == 0.0
    assert marks["at"][20.0] == 1.0
    assert marks["at"][60.0] is None  # past the run's end: not reached, not its last value
    # pooled over SMOOTH iterations, 0.8 is first reached 8 iterations after the jump
    assert marks["first_at_target_min"] == pytest.approx((20 + 8) * 0.5)
    assert marks["minutes"] == pytest.approx(20.0)


def test_curves_plot_and_table_for_several_seeds(tmp_path, capsys):
    a = _run(tmp_path / "a", 0, [0.0] * 20 + [1.0] * 20)
    b = _run(tmp_path / "b", 1, [0.0] * 40, algo="sac")
    ev = _evaluation(tmp_path / "eval_a", "PickCube", 0.9)
    out = tmp_path / "out" / "seeds.png"
    assert curves([f"{a}:{ev}", str(b), f"out={out}", "minutes=5,20"]) == 0
    assert out.stat().st_size > 0
    table = out.with_suffix(".md").read_text()
    assert table == capsys.readouterr().out.split("{")[0]
    rows = [line for line in table.splitlines() if line.startswith("| PickCube")]
    assert rows[0] == ("| PickCube seed 0 | 40 | 0.0 | 0.00 | 1.00 | 14.00 | 20.0 "
                       "| 0.90 [0.80, 0.95] |")
    assert rows[1] == "| PickCube seed 1 (sac) | 40 | 0.0 | 0.00 | 0.00 | - | 20.0 | - |"


def test_curves_refuse_what_is_not_a_run_in_one_line(tmp_path):
    run = _run(tmp_path / "a", 0, [0.0])
    with pytest.raises(ConfigError, match=r"no curve\.jsonl"):
        curves([str(tmp_path)])
    with pytest.raises(ConfigError, match="unknown option"):
        curves([str(run), "colour=red"])
    with pytest.raises(ConfigError, match="not an evaluation of PickCube"):
        curves([f"{run}:{_evaluation(tmp_path / 'ev', 'PushT', 0.5)}"])
    with pytest.raises(ConfigError, match=r"\.png"):
        curves([str(run), f"out={tmp_path / 'x.jpg'}"])
