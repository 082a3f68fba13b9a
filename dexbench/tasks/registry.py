"""Task lookup by name, and the one function that builds an environment for a task."""

from __future__ import annotations

import gymnasium as gym

from dexbench.envs.dex_env import DexEnv
from dexbench.envs.gym_env import DexGymEnv
from dexbench.envs.task_api import Task
from dexbench.tasks import (
    articulation,
    bimanual,
    contact_rich,
    functional,
    longhorizon,
    multigoal,
    nonprehensile,
    primitive,
)

TASK_CLASSES: tuple[type[Task], ...] = (
    primitive.PickCube, primitive.StackCube, primitive.RelocateSphere, primitive.PickUpStick,
    primitive.RelocateObject, primitive.TurnOnSwitch, primitive.PushButton,
    primitive.OpenFaucet, primitive.GraspTwoItems,
    functional.FunctionalPourMug,
    articulation.OpenDrawer, articulation.OpenLaptop,
    nonprehensile.PushT,
    contact_rich.InsertPeg,
    bimanual.BimanualLiftTray,
    multigoal.OpenDrawerRelocateSphere,
    longhorizon.MakeCoffee,
)
TASKS: dict[str, type[Task]] = {t.name: t for t in TASK_CLASSES}


class UnknownTaskError(ValueError):
    """A task name that is not implemented."""


def task_class(name: str) -> type[Task]:
    """The task class called `name`, or an error listing the implemented ones."""
    try:
        return TASKS[name]
    except KeyError:
        raise UnknownTaskError(
            f"unknown task {name!r}; implemented: {', '.join(sorted(TASKS))} "
            "(`python -m dexbench list tasks`)"
        ) from None


def make_env(task: str, embodiment: str | None = None, **kwargs) -> DexEnv:
    """A `DexEnv` for a task by name; `embodiment` defaults to the task's own."""
    cls = task_class(task)
    return DexEnv(cls(), embodiment or cls.default_embodiment, **kwargs)


def make_gym_env(task: str, embodiment: str | None = None, **kwargs) -> DexGymEnv:
    """Entry point behind `gymnasium.make("dexbench/<Task>-v0")`."""
    return DexGymEnv(make_env(task, embodiment, num_envs=1, **kwargs))


def register_gym_envs() -> None:
    """Register every task as `dexbench/<Task>-v0` (idempotent)."""
    for name in TASKS:
        env_id = f"dexbench/{name}-v0"
        if env_id not in gym.registry:
            gym.register(env_id, entry_point=make_gym_env, kwargs={"task": name})
