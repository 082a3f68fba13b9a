"""`python -m dexbench list|inspect|docs|snapshot|validate ...`."""

from __future__ import annotations

import json
import sys

from dexbench.cli.config import env_kwargs, load_config
from dexbench.cli.docs import write_docs
from dexbench.cli.snapshot import snapshot
from dexbench.cli.validate import validate
from dexbench.embodiments.builder import embodiment_names, parse_embodiment
from dexbench.tasks.registry import TASKS, make_env

USAGE = """usage:
  python -m dexbench list tasks
  python -m dexbench list embodiments
  python -m dexbench inspect task=<Task> embodiment=<embodiment> [obs=<preset>]
  python -m dexbench docs             (regenerates docs/tasks.md)
  python -m dexbench snapshot task=<Task> embodiment=<embodiment> visual=<fixed|train|test>
  python -m dexbench validate dataset=<dataset folder> [strict=true]"""


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
    cfg = load_config("config", overrides)
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


def main(argv: list[str]) -> int:
    if argv[:2] == ["list", "tasks"]:
        print(list_tasks())
    elif argv[:2] == ["list", "embodiments"]:
        print(list_embodiments())
    elif argv[:1] == ["inspect"]:
        print(inspect(argv[1:]))
    elif argv[:1] == ["snapshot"]:
        print(f"wrote {snapshot(argv[1:])}")
    elif argv == ["docs"]:
        print(f"wrote {write_docs()}")
    elif argv[:1] == ["validate"]:
        return validate(argv[1:])
    else:
        print(USAGE, file=sys.stderr)
        return 2
    return 0
