"""`python -m dexbench list|inspect|docs|snapshot|validate|merge|curves|split|cloud ...`.

`inspect`, `snapshot` and `validate` are Hydra mains (`--help`, `--cfg job`, ...) picked by
the verb; `list`, `docs`, `merge`, `curves` and `split` take plain arguments.
"""

from __future__ import annotations

import json
import pathlib
import sys

from omegaconf import DictConfig

from dexbench.cli.app import Command, dispatch, register
from dexbench.cli.cloud import CLOUD
from dexbench.cli.config import env_kwargs, load_config
from dexbench.cli.curves import curves
from dexbench.cli.docs import write_docs
from dexbench.cli.errors import run_cli
from dexbench.cli.matrix import MATRIX
from dexbench.cli.merge import merge
from dexbench.cli.serve import SERVE
from dexbench.cli.snapshot import SNAPSHOT
from dexbench.cli.transfer import TRANSFER
from dexbench.cli.validate import VALIDATE
from dexbench.embodiments.builder import embodiment_names, parse_embodiment
from dexbench.tasks.registry import TASKS, make_env

USAGE = """usage:
  python -m dexbench list tasks
  python -m dexbench list embodiments
  python -m dexbench inspect task=<Task> embodiment=<embodiment> [obs=<preset>]
  python -m dexbench docs             (regenerates docs/tasks.md)
  python -m dexbench snapshot task=<Task> embodiment=<embodiment> visual=<fixed|train|test>
  python -m dexbench validate dataset=<dataset folder> [strict=true]
  python -m dexbench serve policy=<dp|dp3|rl> checkpoint=<path> [host=0.0.0.0] [port=8000]
  python -m dexbench cloud task=<Task> embodiment=<embodiment> [seed=0] out=<file>.ply [view=true]
  python -m dexbench cloud dataset=<folder with point clouds> episode=0 frame=10 out=<file>.ply
  python -m dexbench merge <eval run or sweep folder> ... [out=<folder>]
  python -m dexbench curves <rl run>[:<eval run>] ... [out=<png>]   (runs' curves on one plot)
  python -m dexbench split <split>   (its implemented tasks, comma-separated, for -m split_task=)
  python -m dexbench matrix split=<split> episodes=20 jobs=<N>   (the expert on every cell)
  python -m dexbench transfer tasks=[PickCube,...] episodes=10   (expert motion -> other hands)"""


def list_tasks() -> str:
    rows = [(n, c.category, c.default_embodiment, "bimanual" if c.bimanual else "single")
            for n, c in sorted(TASKS.items())]
    return "\n".join(f"{n:<32} {cat:<14} {emb:<28} {arity}" for n, cat, emb, arity in rows)


def list_embodiments() -> str:
    out = []
    for name in embodiment_names():
        e = parse_embodiment(name)
        out.append(f"{name:<28} {e.mount:<9} {e.hand:<8} {'bimanual' if e.bimanual else 'single'}")
    return "\n".join(out)


def inspect(overrides: list[str]) -> str:
    """Programmatic `python -m dexbench inspect ...`: the JSON text."""
    return describe(load_config("inspect", overrides))


def describe(cfg: DictConfig) -> str:
    kwargs = env_kwargs(cfg)
    kwargs["num_envs"] = 1
    env = make_env(**kwargs)
    emb = env.embodiment
    info = {
        "task": env.task.name,
        "category": env.task.category,
        "embodiment": emb.name,
        "action_dim": emb.action_dim,
        "actuators": list(emb.actuators),
        "ctrl_range": emb.ctrl_range.tolist(),
        "proprio_joints": list(emb.proprio_joints),
        "obs": {k: list(v) for k, v in env.obs_shapes().items()},
        "obs_history": env.history,
        "control_dt": env.control_dt,
        "physics_timestep": env.physics.timestep,
        "decimation": env.decimation,
        "episode_steps": env.episode_steps,
        "instruction": env.task.instruction,
    }
    return json.dumps(info, indent=2)


def split_tasks(name: str) -> list[str]:
    """The implemented tasks of split `conf/split/<name>.yaml`, in its order."""
    cfg = load_config("eval", [f"+split={name}"])
    tasks = [str(t) for ts in cfg.split.categories.values() for t in ts]
    return [t for t in tasks if t in TASKS]


def _print_inspect(cfg: DictConfig, _prepared: None, _out: pathlib.Path | None) -> int:
    print(describe(cfg))
    return 0


def _check_inspect(cfg: DictConfig, overrides: list[str]) -> None:
    env_kwargs(cfg)


INSPECT = register(Command("inspect", _print_inspect, _check_inspect))
VERBS = {"inspect": INSPECT, "snapshot": SNAPSHOT, "validate": VALIDATE, "matrix": MATRIX,
         "serve": SERVE, "cloud": CLOUD, "transfer": TRANSFER}


def main(argv: list[str]) -> int:
    """Programmatic `python -m dexbench ...`; 2 with the usage for anything unknown."""
    if argv[:1] and argv[0] in VERBS:
        return VERBS[argv[0]].main(argv[1:])
    if argv[:2] == ["list", "tasks"]:
        print(list_tasks())
    elif argv[:2] == ["list", "embodiments"]:
        print(list_embodiments())
    elif argv == ["docs"]:
        print(f"wrote {write_docs()}")
    elif argv[:1] == ["merge"]:
        return merge(argv[1:])
    elif argv[:1] == ["curves"]:
        return curves(argv[1:])
    elif len(argv) == 2 and argv[0] == "split":
        print(",".join(split_tasks(argv[1])))
    else:
        print(USAGE, file=sys.stderr)
        return 2
    return 0


def entry() -> None:
    """`python -m dexbench <verb> ...`: a Hydra main for inspect, snapshot and validate."""
    if sys.argv[1:2] and sys.argv[1] in VERBS:
        dispatch(VERBS, sys.argv[1:], USAGE)
    else:
        run_cli(main)
