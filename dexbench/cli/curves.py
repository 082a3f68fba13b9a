"""`python -m dexbench curves <rl run> <rl run> ... [out=<png>] [title=<text>] [target=0.8]
[minutes=5,10,15,20]`: several RL runs' training success against wall time on one plot
(e.g. the seeds of one set-up), and a Markdown table per run: iterations, env steps, the
pooled training success at the given minutes, the first minute it reached `target`, and
the evaluator's success with its 95% interval for runs given as `<rl run>:<eval run>`
(an `eval.py policy=rl checkpoint=<rl run>` folder). Written to `out`
(default `runs/rl/curves/<timestamp>.png`, the table beside it as `.md`) and printed."""

from __future__ import annotations

import datetime as dt
import json
import pathlib
from dataclasses import dataclass

import yaml

from dexbench.cli.config import ConfigError, runs_root, write_atomic
from dexbench.rl.curve import milestones, plot_runs

USAGE = ("usage: python -m dexbench curves <rl run folder>[:<eval run folder>] ... "
         "[out=<png>] [title=<text>] [target=0.8] [minutes=5,10,15,20]")
OPTIONS = {"out", "title", "target", "minutes"}


@dataclass(frozen=True)
class RunCurve:
    """One RL run as the table and the plot need it."""

    label: str
    points: list[dict]
    evaluation: dict | None


def _read_json(path: pathlib.Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as err:
        raise ConfigError(f"{path}: {err}; {USAGE}") from None


def load_run(arg: str) -> RunCurve:
    """`<rl run>[:<eval run>]`: its curve, a label (task, seed, algorithm) and the
    evaluation's success with its interval, if any."""
    run_arg, _, eval_arg = arg.partition(":")
    run = pathlib.Path(run_arg)
    curve = run / "curve.jsonl"
    if not curve.is_file():
        raise ConfigError(f"{run}: no curve.jsonl (not an rl.py run folder?); {USAGE}")
    points = [json.loads(line) for line in curve.read_text().splitlines() if line.strip()]
    meta = _read_json(run / "policy.json")
    config = yaml.safe_load((run / "config.yaml").read_text()) or {}
    algo = meta.get("algo", "ppo")
    label = f"{meta['task']} seed {config.get('seed', '?')}" + (
        f" ({algo})" if algo != "ppo" else "")
    evaluation = None
    if eval_arg:
        tasks = _read_json(pathlib.Path(eval_arg) / "results.json").get("tasks") or []
        if len(tasks) != 1 or tasks[0]["task"] != meta["task"]:
            raise ConfigError(f"{eval_arg}: not an evaluation of {meta['task']} alone; {USAGE}")
        evaluation = tasks[0]
    return RunCurve(label, points, evaluation)


def _fmt(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def table(runs: list[RunCurve], minutes: tuple[float, ...], target: float) -> str:
    head = (["run", "iterations", "env steps (M)"]
            + [f"success at {m:g} min" for m in minutes]
            + [f"first >= {target:g} (min)", "minutes", "evaluator"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for run in runs:
        marks = milestones(run.points, minutes, target)
        last = run.points[-1] if run.points else {"iteration": -1, "env_steps": 0}
        ev = run.evaluation
        evaluator = ("-" if ev is None else
                     f"{ev['success_rate']:.2f} [{ev['ci_low']:.2f}, {ev['ci_high']:.2f}]")
        cells = ([run.label, str(last["iteration"] + 1), f"{last['env_steps'] / 1e6:.1f}"]
                 + [_fmt(marks["at"][m]) for m in minutes]
                 + [_fmt(marks["first_at_target_min"]), f"{marks['minutes']:.1f}",
                    evaluator])
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def curves(argv: list[str]) -> int:
    if not argv or {"-h", "--help"} & set(argv):
        print(__doc__)
        return 0 if argv else 2
    options = dict(a.split("=", 1) for a in argv if "=" in a)
    unknown = sorted(set(options) - OPTIONS)
    if unknown:
        raise ConfigError(f"unknown option(s) {unknown}; {USAGE}")
    try:
        target = float(options.get("target", 0.8))
        minutes = tuple(float(m) for m in options.get("minutes", "5,10,15,20").split(","))
    except ValueError:
        raise ConfigError(f"target and minutes take numbers; {USAGE}") from None
    runs = [load_run(a) for a in argv if "=" not in a]
    if not runs:
        raise ConfigError(f"no run folders given; {USAGE}")
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
    out = pathlib.Path(options.get("out", runs_root() / "rl" / "curves" / f"{stamp}.png"))
    if out.suffix != ".png":
        raise ConfigError(f"out={out}: give a .png path; {USAGE}")
    out.parent.mkdir(parents=True, exist_ok=True)
    plot_runs([(r.label, r.points) for r in runs], out, options.get("title", ""))
    text = table(runs, minutes, target)
    write_atomic(out.with_suffix(".md"), text)
    print(text, end="")
    print(json.dumps({"plot": str(out), "table": str(out.with_suffix(".md"))}))
    return 0
