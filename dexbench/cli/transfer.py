"""`python -m dexbench transfer tasks=[...] episodes=10`: cross-embodiment transfer.

For each task, the expert's successful episodes on the source embodiment (default: the
task's own, floating Shadow) become keypoint takes; each take is retargeted to the same
mount with every hand (`other_hands`, and the source hand itself as the identity check)
and played open loop from the same reset. Prints and writes per task and hand the takes
solved and the fingertip retargeting error (`dexbench.teleop.transfer`).
"""

from __future__ import annotations

import dataclasses
import json
import pathlib

from omegaconf import DictConfig

from dexbench.cli.app import Command, register
from dexbench.cli.config import ConfigError, open_run_dir
from dexbench.data.files import write_json
from dexbench.embodiments.builder import other_hands
from dexbench.tasks.registry import task_class
from dexbench.teleop.transfer import record_takes, replay_takes


def _check(cfg: DictConfig, overrides: list[str]) -> None:
    if int(cfg.episodes) < 1:
        raise ConfigError(f"episodes must be >= 1, got {cfg.episodes}")
    for task in cfg.tasks:
        task_class(str(task))


def _table(rows: list[dict]) -> str:
    lines = ["| task | embodiment | solved / takes | fingertip error mean (mm) | p95 (mm) |",
             "|---|---|---:|---:|---:|"]
    lines += [f"| {r['task']} | {r['embodiment']} | {r['successes']}/{r['takes']} | "
              f"{r['tip_error_mm_mean']:.2f} | {r['tip_error_mm_p95']:.2f} |" for r in rows]
    return "\n".join(lines) + "\n"


def _run(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    open_run_dir(out, cfg)
    rows = []
    for task in map(str, cfg.tasks):
        source = str(cfg.source or task_class(task).default_embodiment)
        takes = record_takes(task, source, int(cfg.episodes), int(cfg.seed),
                             out / "takes" / task)
        print(f"{task}: {len(takes)} takes from {cfg.episodes} expert episodes on {source}",
              flush=True)
        if not takes:
            continue
        targets = list(map(str, cfg.targets)) if cfg.targets else [source, *other_hands(source)]
        for target in targets:
            result = dataclasses.asdict(replay_takes(task, target, takes, int(cfg.seed)))
            rows.append({"task": task, "source": source, **result})
            print(f"  {target}: {result['successes']}/{result['takes']} solved, fingertip "
                  f"error {result['tip_error_mm_mean']:.2f} mm mean, "
                  f"{result['tip_error_mm_p95']:.2f} mm p95", flush=True)
    write_json(out / "transfer.json", {"rows": rows})
    (out / "transfer.md").write_text(_table(rows))
    print(json.dumps({"run_dir": str(out), "rows": len(rows)}))
    return 0


def _run_dir(cfg: DictConfig) -> tuple[str, str]:
    return "transfer", "{stamp}"


TRANSFER = register(Command("transfer", _run, _check, _run_dir))
