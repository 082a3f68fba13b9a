"""`python replay.py dataset=<folder> obs=<preset>`: observations from recorded states.

`mode=states` (default) writes a new LeRobotDataset beside the source (or at `out=`)
with the preset's observations regenerated from the recorded simulator states;
`mode=actions` re-simulates the recorded actions instead and reports, per episode, the
largest qpos drift and whether success is reached (a table, and `divergence.json` in
the run folder `runs/replay/<timestamp>-<mode>-<dataset>/`). Task, embodiment, seed and
variation come from the dataset.
"""

from __future__ import annotations

import json
import pathlib
import sys

from omegaconf import DictConfig

from dexbench.cli.app import Command, hydra_main, register
from dexbench.cli.config import ConfigError, env_kwargs, open_run_dir
from dexbench.data.files import write_json
from dexbench.data.meta import DatasetError, read_meta, verify_files
from dexbench.data.replay import default_out, replay_actions, replay_states

# Settings a dataset fixes; replay takes only rendering and threading ones from the config.
FROM_DATASET = ("task", "embodiment", "seed", "num_envs", "obs", "backend", "physics",
                "visual", "physical")


def _table(report: dict) -> str:
    lines = [f"{'episode':>7}  {'key':<14} {'frames':>6}  {'max |dqpos|':>11}  "
             f"{'success at':>10}  {'recorded':>8}  final"]
    for r in report["episodes"]:
        at = r["success_step"] if r["success_step"] >= 0 else "-"
        lines.append(f"{r['episode_index']:>7}  {'/'.join(map(str, r['key'])):<14} "
                     f"{r['length']:>6}  {r['max_abs_qpos_error']:>11.3e}  {at:>10}  "
                     f"{r['recorded_success_step']:>8}  {'yes' if r['final_success'] else 'no'}")
    return "\n".join(lines)


def _obs(cfg: DictConfig) -> str | list[str]:
    return cfg.obs if isinstance(cfg.obs, str) else list(cfg.obs)


def check(cfg: DictConfig, overrides: list[str]) -> dict:
    """The settings, the mode and the dataset (whole, checksums verified); the env's
    rendering and threading settings."""
    if not cfg.dataset:
        raise ConfigError("replay needs dataset=<folder of a collected dataset>")
    settings = {k: v for k, v in env_kwargs(cfg).items() if k not in FROM_DATASET}
    if cfg.mode not in ("states", "actions"):
        raise ConfigError(f"unknown mode {cfg.mode!r}; modes: states, actions")
    source = pathlib.Path(cfg.dataset)
    verify_files(source, read_meta(source))
    if cfg.mode == "states":
        out = pathlib.Path(cfg.out) if cfg.out else default_out(source, _obs(cfg))
        if out.exists():
            raise DatasetError(f"{out} exists; remove it or pass out=<another folder>")
    return settings


def run_dir(cfg: DictConfig) -> tuple[str, str]:
    return "replay", f"{{stamp}}-{cfg.mode}-{pathlib.Path(str(cfg.dataset)).name}"


def run(cfg: DictConfig, settings: dict, out_dir: pathlib.Path) -> int:
    source = pathlib.Path(cfg.dataset)
    progress = bool(cfg.progress)
    run_folder = open_run_dir(out_dir, cfg)
    if cfg.mode == "states":
        obs = _obs(cfg)
        out = pathlib.Path(cfg.out) if cfg.out else default_out(source, obs)
        changes = replay_states(source, out, obs, num_envs=int(cfg.num_envs),
                                force=bool(cfg.force), progress=progress, **settings)
        for change in changes:
            print(f"warning: recorded with other code: {change}", file=sys.stderr)
        print(f"wrote {out}")
        print(json.dumps({"dataset": str(out), "source": str(source), "obs": obs}))
    else:
        report = replay_actions(source, num_envs=int(cfg.num_envs), progress=progress,
                                **settings)
        write_json(run_folder / "divergence.json", report)
        print(_table(report))
        print(json.dumps({"divergence": str(run_folder / "divergence.json"),
                          "max_abs_qpos_error": report["max_abs_qpos_error"],
                          "successes": report["successes"],
                          "episodes": len(report["episodes"])}))
    return 0


COMMAND = register(Command("replay", run, check, run_dir))
main = COMMAND.main
hydra_entry = hydra_main(COMMAND)
