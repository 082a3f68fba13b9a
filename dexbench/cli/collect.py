"""`python collect.py task=<T> embodiment=<E> num_demos=50`: scripted demonstrations.

Runs the task's expert (`dexbench.experts.make_expert`) on `num_envs` environments and
writes a LeRobotDataset to `runs/datasets/<task>/<embodiment>/<name>/` (how, in
`dexbench.data.collect`); the same command again resumes an interrupted run.
`protocol=paper` collects the paper's set in one go: per task, `num_demos` with its
default embodiment and `other_hands_demos` with each other hand on the same mount, and
writes one summary in its run folder `runs/collect/<timestamp>-paper/`; a single
collection's run folder `runs/collect/<timestamp>-<task>/` holds its config and log.
"""

from __future__ import annotations

import json
import pathlib
import sys
from collections.abc import Callable

from omegaconf import DictConfig, OmegaConf

from dexbench import experts
from dexbench.cli.app import Command, hydra_main, register
from dexbench.cli.config import ConfigError, dataset_path, env_kwargs, open_run_dir
from dexbench.data.collect import CollectSettings, Staging, collect
from dexbench.data.files import write_json
from dexbench.embodiments.builder import other_hands as same_mount_hands
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.scene import check_pair
from dexbench.experts.base import Expert
from dexbench.tasks.registry import TASKS, make_env, task_class

ExpertFactory = Callable[[DexEnv], Expert]


class NoExpertError(ConfigError):
    """The expert factory has no script for this task or embodiment."""


def dataset_dir(cfg: DictConfig, task: str, embodiment: str) -> pathlib.Path:
    if cfg.out:
        return pathlib.Path(cfg.out)
    return dataset_path(task, embodiment, cfg.name or f"seed{cfg.seed}")


def collect_settings(cfg: DictConfig) -> CollectSettings:
    """The recording settings of a collect (or teleop) config, checked."""
    num_demos, post = int(cfg.num_demos), int(cfg.post_success_steps)
    attempts = int(cfg.max_attempts) if cfg.max_attempts is not None else 5 * num_demos
    if num_demos < 1 or post < 0 or attempts < num_demos:
        raise ConfigError(f"need num_demos >= 1, post_success_steps >= 0 and max_attempts >= "
                          f"num_demos; got {num_demos}, {post}, {attempts}")
    return CollectSettings(num_demos, attempts, post, bool(cfg.get("keep_failures", False)))


def _checked(cfg: DictConfig) -> tuple[dict, CollectSettings]:
    """The env's keyword arguments and the settings, checked before anything is built."""
    kwargs = env_kwargs(cfg)
    if cfg.obs != "state":
        raise ConfigError("collect records simulator states and state observations; render "
                          f"obs={cfg.obs} afterwards with `python replay.py dataset=<folder> "
                          f"obs={cfg.obs}`")
    return kwargs, collect_settings(cfg)


def collect_one(cfg: DictConfig, make_expert: ExpertFactory, on_episode=None) -> dict:
    """One dataset for `cfg.task` on `cfg.embodiment`; its statistics."""
    kwargs, settings = _checked(cfg)
    env = make_env(**kwargs)
    out = dataset_dir(cfg, env.task.name, env.embodiment.name)
    try:
        expert = make_expert(env)
    except (ValueError, NotImplementedError) as err:
        raise NoExpertError(str(err)) from None
    try:
        return collect(env, expert, out, settings, OmegaConf.to_container(cfg),
                       on_episode=on_episode, progress=bool(cfg.progress))
    except KeyboardInterrupt:
        print(f"\ninterrupted: kept demonstrations are safe in {Staging(out).dir}; run the "
              "same command again to continue", file=sys.stderr)
        raise


def paper_plan(tasks: list[str], num_demos: int, other_hands: int) -> list[tuple[str, str, int]]:
    """(task, embodiment, demos): the default embodiment, then every other hand on its
    mount (and arity); entries asking for no demos are left out."""
    plan = []
    for task in tasks:
        default = task_class(task).default_embodiment
        plan.append((task, default, num_demos))
        plan += [(task, name, other_hands) for name in same_mount_hands(default)]
    return [entry for entry in plan if entry[2] > 0]


def check(cfg: DictConfig, overrides: list[str]) -> None:
    """The settings and the task x embodiment pair (or the protocol's tasks)."""
    _checked(cfg)
    if cfg.protocol == "paper":
        if cfg.out:
            raise ConfigError("out= names one dataset; protocol=paper writes one per task and "
                              "embodiment under runs/datasets (name= picks their folder name)")
        for task in cfg.tasks or []:
            task_class(str(task))
    elif cfg.protocol is None:
        embodiment = cfg.embodiment or task_class(cfg.task).default_embodiment
        check_pair(task_class(cfg.task), embodiment)
    else:
        raise ConfigError(f"unknown protocol {cfg.protocol!r}; protocols: paper")


def run_dir(cfg: DictConfig) -> tuple[str, str]:
    label = "paper" if cfg.protocol == "paper" else str(cfg.task)
    return "collect", f"{{stamp}}-{label}"


def run_protocol(cfg: DictConfig, make_expert: ExpertFactory, run_dir: pathlib.Path) -> dict:
    """`protocol=paper`: every dataset of the plan; one summary JSON in `run_dir`. A task
    or hand without an expert is listed as skipped, and the protocol goes on."""
    tasks = list(cfg.tasks) if cfg.tasks else list(TASKS)
    plan = paper_plan(tasks, int(cfg.num_demos), int(cfg.other_hands_demos))
    run_dir = open_run_dir(run_dir, cfg)
    results, skipped = [], []
    for task, embodiment, demos in plan:
        sub = OmegaConf.merge(cfg, {"task": task, "embodiment": embodiment,
                                    "num_demos": demos, "protocol": None})
        try:
            results.append(collect_one(sub, make_expert))
        except NoExpertError as err:
            skipped.append({"task": task, "embodiment": embodiment, "reason": str(err)})
            print(f"skipped {task} on {embodiment}: {err}", file=sys.stderr)
    summary = {"protocol": "paper", "tasks": tasks,
               "complete": not skipped and all(r["complete"] for r in results),
               "demos": sum(r["successes"] for r in results),
               "attempts": sum(r["attempts"] for r in results),
               "datasets": results, "skipped": skipped,
               "summary": str(run_dir / "summary.json")}
    write_json(run_dir / "summary.json", summary)
    return summary


def _line(stats: dict) -> str:
    where = stats.get("dataset", "no dataset written")
    per_step = f", {stats['bytes_per_step']:,.0f} bytes/step" if "bytes_per_step" in stats else ""
    return (f"{stats['task']} on {stats['embodiment']}: kept {stats['successes']}/"
            f"{stats['num_demos']} ({stats['attempts']} attempts, success rate "
            f"{stats['success_rate']:.2f}{per_step}) -> {where}")


def run(cfg: DictConfig, _prepared: None, out: pathlib.Path,
        make_expert: ExpertFactory | None = None) -> int:
    factory = make_expert or experts.make_expert
    try:
        if cfg.protocol == "paper":
            result = run_protocol(cfg, factory, out)
            for stats in result["datasets"]:
                print(_line(stats))
        else:
            open_run_dir(out, cfg)
            result = collect_one(cfg, factory)
            print(_line(result))
    except KeyboardInterrupt:
        return 130
    print(json.dumps(result))
    return 0 if result["complete"] else 1


COMMAND = register(Command("collect", run, check, run_dir))
hydra_entry = hydra_main(COMMAND)


def main(argv: list[str], make_expert: ExpertFactory | None = None) -> int:
    """Programmatic `python collect.py ...`; `make_expert` replaces the experts."""
    if make_expert is None:
        return COMMAND.main(argv)
    with_expert = Command("collect", lambda cfg, p, out: run(cfg, p, out, make_expert),
                          check, run_dir)
    return with_expert.main(argv)
