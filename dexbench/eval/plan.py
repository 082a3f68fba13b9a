"""Which tasks an evaluation runs, on which embodiment, with which checkpoint, and why a
task cannot run (not implemented yet, wrong number of hands, no checkpoint for it).

Everything here is checked before the first episode, so a long split run does not fail
half way for a reason known at the start.
"""

from __future__ import annotations

import pathlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from dexbench.envs.scene import pair_problem
from dexbench.policies.common.protocol import PolicySpec
from dexbench.policies.registry import policy_module
from dexbench.tasks.registry import TASKS


@dataclass(frozen=True)
class TaskPlan:
    task: str
    category: str
    embodiment: str
    checkpoint: str | None
    spec: PolicySpec


def checkpoint_for(checkpoint: str | None, task: str, embodiment: str, kind: str) -> str | None:
    """A folder laid out as `train.py` writes runs (`<folder>/<task>/<embodiment>/<kind>/`)
    or holding one entry per task (`<folder>/<task>`) gives each task its own checkpoint;
    anything else is passed to the policy kind as it is."""
    if checkpoint is None:
        return None
    root = pathlib.Path(checkpoint)
    for per_task in (root / task / embodiment / kind, root / task):
        if per_task.exists():
            return str(per_task)
    return checkpoint


def plan_task(task: str, category: str, kind: str, checkpoint: str | None,
              embodiment: str | None, options: Mapping[str, Any]) -> TaskPlan | str:
    """The plan for policy `kind` on `task`, or the reason it cannot be evaluated."""
    if task not in TASKS:
        return "not implemented yet (`python -m dexbench list tasks` lists those that are)"
    cls = TASKS[task]
    ckpt = checkpoint_for(checkpoint, task, embodiment or cls.default_embodiment, kind)
    try:
        spec = policy_module(kind).spec(ckpt, options)
    except (ValueError, OSError) as err:
        return f"policy cannot be loaded: {err}"
    if spec.task is not None and spec.task != task:
        return (f"the checkpoint was trained on {spec.task}; give a folder with one "
                "checkpoint per task (<folder>/<task>)")
    name = embodiment or spec.embodiment or cls.default_embodiment
    problem = pair_problem(cls, name)
    if problem is not None:
        return f"the task {problem}"
    return TaskPlan(task, category, name, ckpt, spec)
