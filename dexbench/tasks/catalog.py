"""Where tasks register themselves: `@register` on the class, in the module defining it.

`dexbench.tasks.registry` imports every module of this package, so a new task needs
no list to be edited anywhere.
"""

from __future__ import annotations

from dexbench.envs.task_api import Task

_TASKS: dict[str, type[Task]] = {}


def register[T: type[Task]](cls: T) -> T:
    """Class decorator: make `cls` a benchmark task under `cls.name`."""
    if cls.name in _TASKS and _TASKS[cls.name] is not cls:
        raise ValueError(f"two tasks are called {cls.name!r}: {_TASKS[cls.name].__module__} "
                         f"and {cls.__module__}")
    _TASKS[cls.name] = cls
    return cls


def registered() -> dict[str, type[Task]]:
    """Every task registered so far, by name, in registration order."""
    return dict(_TASKS)
