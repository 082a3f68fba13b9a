"""`python replay.py dataset=<folder> obs=<preset>`: observations from recorded states.

`mode=states` (default) writes a new LeRobotDataset beside the source (or at `out=`)
with the preset's observations regenerated from the recorded simulator states;
`mode=actions` re-simulates the recorded actions instead and reports, per episode, the
largest qpos drift and whether success is reached (a table, and JSON under
`runs/replay/`). Task, embodiment, seed and variation come from the dataset.
"""

from __future__ import annotations

import json
import pathlib
import sys

from dexbench.cli.config import ConfigError, env_kwargs, load_config, new_run_dir
from dexbench.data.files import write_json
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


def main(argv: list[str]) -> int:
    cfg = load_config("replay", argv)
    if not cfg.dataset:
        raise ConfigError("replay needs dataset=<folder of a collected dataset>")
    source = pathlib.Path(cfg.dataset)
    settings = {k: v for k, v in env_kwargs(cfg).items() if k not in FROM_DATASET}
    progress = bool(cfg.progress)
    if cfg.mode == "states":
        obs = cfg.obs if isinstance(cfg.obs, str) else list(cfg.obs)
        out = pathlib.Path(cfg.out) if cfg.out else default_out(source, obs)
        changes = replay_states(source, out, obs, num_envs=int(cfg.num_envs),
                                force=bool(cfg.force), progress=progress, **settings)
        for change in changes:
            print(f"warning: recorded with other code: {change}", file=sys.stderr)
        print(f"wrote {out}")
        print(json.dumps({"dataset": str(out), "source": str(source), "obs": obs}))
    elif cfg.mode == "actions":
        report = replay_actions(source, num_envs=int(cfg.num_envs), progress=progress,
                                **settings)
        run_dir = new_run_dir("replay", f"actions-{source.name}", cfg)
        write_json(run_dir / "divergence.json", report)
        print(_table(report))
        print(json.dumps({"divergence": str(run_dir / "divergence.json"),
                          "max_abs_qpos_error": report["max_abs_qpos_error"],
                          "successes": report["successes"],
                          "episodes": len(report["episodes"])}))
    else:
        raise ConfigError(f"unknown mode {cfg.mode!r}; modes: states, actions")
    return 0
