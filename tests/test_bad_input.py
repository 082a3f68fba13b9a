"""Bad input on the command line: one `error: ...` line on stderr that says what to do,
a non-zero exit, no traceback, and nothing written.

Every case runs an entry point the way `python <script> key=value ...` does: the
script's own `__main__` path with `sys.argv` set (in-process through `runpy`, to pay
the imports once), and a few as real subprocesses. The cases name scripts and
arguments only, so they hold whatever the scripts call.
"""

from __future__ import annotations

import os
import pathlib
import runpy
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
MODULE = "-m dexbench"
BIMANUAL_ON_SINGLE = ("needs one hand; embodiment bimanual_floating_shadow has two hands: use "
                      "embodiment=floating_shadow")


def run_in_process(args: list[str], monkeypatch, capsys) -> tuple[int, str]:
    """(exit status, stderr) of `python <args>`, run in this process."""
    script, *argv = args
    capsys.readouterr()
    monkeypatch.setattr(sys, "argv", [script, *argv])
    with pytest.raises(SystemExit) as stop:
        if script == MODULE:
            runpy.run_module("dexbench", run_name="__main__", alter_sys=True)
        else:
            runpy.run_path(str(ROOT / script), run_name="__main__")
    return stop.value.code, capsys.readouterr().err


def run_subprocess(args: list[str]) -> tuple[int, str]:
    command = args[0].split() + args[1:] if args[0] == MODULE else [str(ROOT / args[0]),
                                                                     *args[1:]]
    out = subprocess.run([sys.executable, *command], capture_output=True, text=True,
                         timeout=120, cwd=ROOT, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    return out.returncode, out.stderr


def assert_one_error(code: int, stderr: str, needle: str) -> str:
    """The one `error:` line, after checking the exit status and that it is all."""
    assert code not in (0, None), stderr
    assert "Traceback" not in stderr, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), stderr
    assert needle in lines[0], lines[0]
    return lines[0]


def files_under(path: pathlib.Path) -> list[pathlib.Path]:
    return sorted(p for p in path.rglob("*") if p.is_file()) if path.exists() else []


@pytest.fixture(scope="module")
def datasets(tmp_path_factory) -> tuple[pathlib.Path, pathlib.Path]:
    """(intact, damaged): one expert demonstration by `collect.py`, and a copy with 8
    bytes of its data file overwritten."""
    root = tmp_path_factory.mktemp("datasets")
    good = root / "good"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sys, "argv", ["collect.py", "num_demos=1", "num_envs=1", "sim.nthread=1",
                                 "progress=false", f"out={good}"])
        with pytest.raises(SystemExit) as stop:
            runpy.run_path(str(ROOT / "collect.py"), run_name="__main__")
    assert stop.value.code == 0
    bad = root / "bad"
    shutil.copytree(good, bad)
    data = next(bad.glob("data/chunk-*/file-*.parquet"))
    raw = bytearray(data.read_bytes())
    middle = len(raw) // 2
    raw[middle:middle + 8] = bytes(255 - b for b in raw[middle:middle + 8])
    data.write_bytes(bytes(raw))
    return good, bad


CASES = {
    "bench num_envs=0": (["bench.py", "sim", "num_envs=0"], "num_envs must be"),
    "bench num_envs<0": (["bench.py", "sim", "num_envs=-2"], "num_envs must be"),
    "collect num_envs=0": (["collect.py", "num_envs=0"], "num_envs must be"),
    "collect paper num_envs<0": (["collect.py", "protocol=paper", "tasks=[PickCube]",
                                  "num_envs=-1"], "num_envs must be"),
    "inspect obs": ([MODULE, "inspect", "obs=nonsense"], "unknown observation preset"),
    "replay obs": (["replay.py", "dataset=nowhere", "obs=nonsense"],
                   "unknown observation preset"),
    "eval expert obs": (["eval.py", "policy=expert", "obs=nonsense"],
                        "unknown observation preset"),
    "eval expert other obs": (["eval.py", "policy=expert", "obs=rgb"], "drop obs="),
    "eval dp no checkpoint": (["eval.py", "policy=dp"], "policy=dp needs checkpoint="),
    "eval dp3 no checkpoint": (["eval.py", "policy=dp3"], "policy=dp3 needs checkpoint="),
    "eval missing checkpoint": (["eval.py", "policy=dp", "checkpoint=nowhere"],
                                "PickCube: policy cannot be loaded: no checkpoint at nowhere"),
    "collect bimanual": (["collect.py", "embodiment=bimanual_floating_shadow"],
                         BIMANUAL_ON_SINGLE),
    "train bimanual": (["train.py", "policy=dp", "embodiment=bimanual_floating_shadow"],
                       BIMANUAL_ON_SINGLE),
    "bench bimanual": (["bench.py", "sim", "embodiment=bimanual_floating_shadow"],
                       BIMANUAL_ON_SINGLE),
    "snapshot bimanual": ([MODULE, "snapshot", "embodiment=bimanual_floating_shadow"],
                          BIMANUAL_ON_SINGLE),
    "eval bimanual": (["eval.py", "policy=expert", "embodiment=bimanual_floating_shadow"],
                      BIMANUAL_ON_SINGLE),
    "rl bimanual": (["rl.py", "sim.backend=cpu", "embodiment=bimanual_floating_shadow"],
                    BIMANUAL_ON_SINGLE),
    "collect one hand on bimanual": (["collect.py", "task=BimanualLiftTray",
                                      "embodiment=floating_shadow"],
                                     "BimanualLiftTray needs two hands; embodiment "
                                     "floating_shadow has one hand: use "
                                     "embodiment=bimanual_floating_shadow"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_is_one_line_and_writes_nothing(case, tmp_path, monkeypatch, capsys):
    args, needle = CASES[case]
    line = assert_one_error(*run_in_process(args, monkeypatch, capsys), needle)
    assert "other 0" not in line and "1 of the 1" not in line
    assert files_under(tmp_path / "runs") == []


def test_bad_input_in_a_real_process(tmp_path):
    args, needle = CASES["eval dp no checkpoint"]
    assert_one_error(*run_subprocess(args), needle)
    assert files_under(tmp_path / "runs") == []


def test_damaged_dataset_is_refused_before_use(datasets, tmp_path, monkeypatch, capsys):
    """8 bytes overwritten: replay (both modes) and training stop, naming the file."""
    good, bad = datasets
    before = files_under(bad.parent)
    assert run_in_process([MODULE, "validate", f"dataset={good}", "check_code=false"],
                          monkeypatch, capsys)[0] == 0
    for args in (["replay.py", f"dataset={bad}", "obs=state"],
                 ["replay.py", f"dataset={bad}", "mode=actions"],
                 ["train.py", "policy=dp", f"dataset={bad}", "device=cpu"]):
        line = assert_one_error(*run_in_process(args, monkeypatch, capsys), "checksum")
        assert "file-000.parquet" in line and "dexbench validate" in line
    assert files_under(bad.parent) == before  # no replayed dataset, not even a temp one
    assert files_under(tmp_path / "runs") == []
    assert_one_error(*run_subprocess(["replay.py", f"dataset={bad}", "obs=state"]),
                     "checksum")


def test_a_failed_eval_run_logs_why_it_stopped(tmp_path, monkeypatch, capsys):
    args = ["eval.py", "policy=expert", "episodes=1", "horizon=2", "video.episodes=[0]",
            "video.camera=nope", "sim.nthread=1", "progress=false"]
    line = assert_one_error(*run_in_process(args, monkeypatch, capsys), "no camera 'nope'")
    (log,) = (tmp_path / "runs").rglob("eval.log")
    assert log.read_text().splitlines()[-1].endswith(line)
