"""The cross-embodiment matrix: cell enumeration, the tables and heatmap from a folder
(means, infeasible cells, acceptance numbers), the feasibility verdict and IK reach, and
resuming (a complete cell is not run again)."""

from __future__ import annotations

import csv
import json
import pathlib

import numpy as np
import pytest
from omegaconf import OmegaConf

from dexbench.cli import matrix as matrix_cli
from dexbench.cli.config import ConfigError, runs_root
from dexbench.embodiments.builder import HOME_PALM_ROT, HOME_PALM_X, HOME_PALM_Z
from dexbench.eval import feasibility, matrix
from dexbench.eval.feasibility import POS_TOL, ROT_TOL, verdict
from dexbench.eval.runner import run_episodes
from dexbench.policies.registry import policy_module
from dexbench.tasks.registry import make_env

SINGLE = ["floating_leap", "fr3_leap", "ur10e_leap"]


def test_pairs_match_arity_in_registry_order() -> None:
    cells = matrix.pairs([("PickCube", False), ("BimanualLiftTray", True)])
    single = [e for t, e in cells if t == "PickCube"]
    double = [e for t, e in cells if t == "BimanualLiftTray"]
    assert len(single) == len(double) == 24
    assert not any(e.startswith("bimanual_") for e in single)
    assert all(e.startswith("bimanual_") for e in double)
    narrowed = matrix.pairs([("PickCube", False), ("BimanualLiftTray", True)],
                            ["bimanual_fr3_leap", "ur10e_leap", "fr3_leap"])
    assert narrowed == [("PickCube", "fr3_leap"), ("PickCube", "ur10e_leap"),
                        ("BimanualLiftTray", "bimanual_fr3_leap")]


def _measurement(embodiment: str, reach_q: list[float], success: list[bool],
                 rot_q: float = 0.01) -> dict:
    """A stored measurement: per episode its reach and, as given, its orientation."""
    return {"embodiment": embodiment, "reference": feasibility.reference_embodiment(embodiment),
            "quantile": 95.0,
            "episodes": [{"reference_success": s, "poses": 10, "pos_q": r, "rot_q": rot_q,
                          "reach_q": r, "pos_max": r, "rot_max": rot_q, "reach_max": r}
                         for r, s in zip(reach_q, success, strict=True)]}


def test_verdict() -> None:
    assert verdict(None) == (True, "not measured")
    assert verdict(feasibility.reference_measurement("floating_leap"))[0]
    far = 10 * POS_TOL
    assert verdict(_measurement("fr3_leap", [0.001, 0.001, far], [True] * 3))[0]
    ok, why = verdict(_measurement("fr3_leap", [far, far, 0.001], [True] * 3))
    assert not ok and "1/3" in why
    # only episodes the reference solved count; none solved: not measured, feasible
    assert verdict(_measurement("fr3_leap", [0.001, far, far], [True, False, False]))[0]
    ok, why = verdict(_measurement("fr3_leap", [far, far], [False, False]))
    assert ok and why.startswith("not measured")
    # reached but not in the plan's orientation: feasible, flagged pose-limited
    wrist = _measurement("fr3_leap", [0.001, 0.001], [True, True], rot_q=2 * ROT_TOL)
    assert verdict(wrist)[0] and feasibility.pose_limited(wrist)
    assert not feasibility.pose_limited(_measurement("fr3_leap", [0.001], [True]))


def test_ik_residuals_home_reached_far_pose_missed() -> None:
    home = np.array([[[HOME_PALM_X, 0.0, HOME_PALM_Z]]])
    far = np.array([[[HOME_PALM_X + 2.0, 0.0, HOME_PALM_Z]]])
    rot = np.array([[HOME_PALM_ROT]])
    res = feasibility.ik_residuals("fr3_leap", np.concatenate([home, far]),
                                   np.concatenate([rot, rot]))
    assert res.shape == (2, 1, 3)
    assert res[0, 0, 0] < 1e-3 and res[0, 0, 1] < 1e-2 and res[0, 0, 2] < 1e-3
    assert res[1, 0, 0] > 1.0 and res[1, 0, 2] > 1.0


def _cell(task: str, emb: str, rate: float | None, feasible: bool = True,
          complete: bool = True) -> matrix.Cell:
    bimanual = emb.startswith("bimanual_")
    if rate is None:
        return matrix.Cell(task, emb, bimanual, feasible=feasible)
    return matrix.Cell(task, emb, bimanual, 20, round(20 * rate), rate, 0.0, 1.0, complete,
                       feasible, "reference mount" if feasible else "unreachable")


def test_build_means_exclude_infeasible_and_pending() -> None:
    cells = [_cell("A", "floating_leap", 1.0), _cell("A", "fr3_leap", 0.0, feasible=False),
             _cell("A", "ur10e_leap", 0.6),
             _cell("B", "floating_leap", 0.4), _cell("B", "fr3_leap", 0.2),
             _cell("B", "ur10e_leap", None),
             _cell("T", "bimanual_fr3_leap", 0.9)]
    s = matrix.build(cells, ["A", "B", "T"])
    single, double = s["panels"]
    assert single["tasks"] == ["A", "B"] and single["embodiments"] == SINGLE
    assert single["task_means"] == pytest.approx({"A": 0.8, "B": 0.3})
    assert single["embodiment_means"] == pytest.approx(
        {"floating_leap": 0.7, "fr3_leap": 0.2, "ur10e_leap": 0.6})
    assert single["mean"] == pytest.approx(2.2 / 4)
    assert double["embodiments"] == ["bimanual_fr3_leap"] and double["mean"] == 0.9
    # 5 feasible evaluated cells, 3 at >= 0.5
    assert (s["feasible_evaluated"], s["feasible_at_bar"]) == (5, 3)
    assert s["share_feasible_at_bar"] == pytest.approx(0.6)
    # fr3_leap: 0.2 on its one feasible task
    assert s["embodiments_failing"] == ["fr3_leap"] and s["embodiments_ok"] == 3
    # B: 0.4 and 0.2
    assert s["tasks_failing"] == ["B"] and s["tasks_ok"] == 2
    assert s["accepted"] == {"cells": False, "embodiments": False, "tasks": False}
    assert [(c["task"], c["embodiment"]) for c in s["infeasible"]] == [("A", "fr3_leap")]
    assert [(c["task"], c["embodiment"]) for c in s["pending"]] == [("B", "ur10e_leap")]


def _write_cell(root: pathlib.Path, task: str, emb: str, successes: int, episodes: int,
                pos_q: float | None = None, rot_q: float = 0.01) -> None:
    folder = matrix.cell_dir(root, task, emb)
    folder.mkdir(parents=True)
    rate = successes / episodes
    (folder / "results.json").write_text(json.dumps({
        "complete": True, "episodes_per_task": episodes,
        "tasks": [{"task": task, "episodes": episodes, "successes": successes,
                   "success_rate": rate, "ci_low": 0.0, "ci_high": 1.0}]}))
    measurement = (feasibility.reference_measurement(emb) if pos_q is None
                   else _measurement(emb, [pos_q] * 3, [True] * 3, rot_q))
    (folder / matrix.FEASIBILITY_FILE).write_text(json.dumps(measurement))


def test_outputs_rebuilt_from_folder(tmp_path: pathlib.Path) -> None:
    root = tmp_path / "m"
    root.mkdir()
    (root / matrix.MATRIX_FILE).write_text(json.dumps({
        "split": "demo", "episodes": 4,
        "tasks": [{"task": "PushT", "category": "c", "bimanual": False},
                  {"task": "BimanualLiftTray", "category": "c", "bimanual": True}]}))
    _write_cell(root, "PushT", "floating_leap", 4, 4)
    _write_cell(root, "PushT", "fr3_leap", 1, 4, pos_q=0.3)  # infeasible
    _write_cell(root, "PushT", "ur10e_leap", 2, 4, pos_q=0.0, rot_q=1.0)  # wrist-limited
    _write_cell(root, "BimanualLiftTray", "bimanual_xarm7_leap", 0, 4, pos_q=0.0)
    s = matrix.write_outputs(root)
    for name in (matrix.PNG_FILE, matrix.CSV_FILE, matrix.MD_FILE, matrix.SUMMARY_FILE):
        assert (root / name).stat().st_size > 0
    assert json.loads((root / matrix.SUMMARY_FILE).read_text())["feasible_evaluated"] == 3
    assert s["share_feasible_at_bar"] == pytest.approx(2 / 3)
    assert s["pose_limited"] == ["PushT x ur10e_leap"]
    md = (root / matrix.MD_FILE).read_text()
    assert "| PushT | 1.00 | (0.25) | 0.50 | **0.75** |" in md
    assert "PushT x fr3_leap (0.25): 0/3 solved probe episodes within reach" in md
    rows = list(csv.DictReader((root / matrix.CSV_FILE).read_text().splitlines()))
    fr3 = next(r for r in rows if r["row"] == "cell" and r["embodiment"] == "fr3_leap")
    assert fr3["feasible"] == "0" and fr3["success_rate"] == "0.2500"
    means = {r["task"]: r["success_rate"] for r in rows if r["row"] == "task mean"}
    assert means == {"PushT": "0.7500", "BimanualLiftTray": "0.0000"}



def test_check_rejects_unknown_subsets() -> None:
    with pytest.raises(ConfigError, match="not implemented tasks of split"):
        matrix_cli.main(["tasks=[PickCube]"])
    with pytest.raises(ValueError, match="unknown embodiment"):
        matrix_cli.main(["tasks=[PushT]", "embodiments=[fr3_nohand]"])
    with pytest.raises(ConfigError, match="no \\(task, embodiment\\) cell"):
        matrix_cli.main(["tasks=[PushT]", "embodiments=[bimanual_fr3_leap]"])


def test_resume_skips_complete_cells(monkeypatch: pytest.MonkeyPatch,
                                     capsys: pytest.CaptureFixture) -> None:
    """One real tiny cell, then the same command again: nothing is run."""
    argv = ["tasks=[PushT]", "embodiments=[floating_leap]", "episodes=1"]
    assert matrix_cli.main(argv) == 0
    root = runs_root() / "matrix" / "baseline19"
    cell = matrix.read_cell(root, "PushT", "floating_leap")
    assert cell.episodes == 1 and cell.complete and cell.feasible
    first = capsys.readouterr().out
    assert "[1/1] PushT x floating_leap:" in first

    def never(*args: object) -> None:
        raise AssertionError("a complete cell ran again")

    monkeypatch.setattr(matrix_cli, "run_cell", never)
    assert matrix_cli.main(argv) == 0
    assert "1 cells, 1 complete, 0 to evaluate" in capsys.readouterr().out
    # A config library that hands sequences back as tuples (omegaconf 2.4 for structured
    # configs) still matches the lists matrix.json stored: the folder resumes.
    plain = OmegaConf.to_container

    def tuples(value: object) -> object:
        if isinstance(value, list):
            return tuple(tuples(v) for v in value)
        return {k: tuples(v) for k, v in value.items()} if isinstance(value, dict) else value

    monkeypatch.setattr(OmegaConf, "to_container", lambda *a, **k: tuples(plain(*a, **k)))
    assert matrix_cli.main(argv) == 0
    assert "1 cells, 1 complete, 0 to evaluate" in capsys.readouterr().out
    monkeypatch.setattr(OmegaConf, "to_container", plain)
    with pytest.raises(ConfigError, match="other settings \\(episodes\\)"):
        matrix_cli.main([*argv[:2], "episodes=2"])


def test_palm_recorder_runs_the_evaluator_loop() -> None:
    """The reach test records palm paths through `run_episodes`, which passes `observe=`."""
    env = make_env("PickCube", "floating_shadow", num_envs=1, seed=0, nthread=1)
    env.episode_steps = 5
    recorder = feasibility._PalmRecorder(env)
    ends = []
    run_episodes(recorder, policy_module("expert").build(None, env, "cpu", {}), [0], 0,
                 ends.append)
    assert [e.steps for e in ends] == [5] and len(recorder.paths[0]) == 6
