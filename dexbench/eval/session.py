"""One evaluation run: which tasks it plans, its run folder and identity, resuming, the
batched rollouts per task and the result files.

`EvalSpec` says everything a run is; the CLI (`dexbench/cli/eval.py`) only builds one
from a config. A run folder holds `run.json` (the identity: what fixes its episodes and
outcomes, the backend included, so a resumed run cannot change them), `config.yaml`,
`command.txt`, `episodes.jsonl`, `results.{md,csv,tex,json}`, the chart, `eval.log` and
videos. On the warp backend every pending episode of a task runs at once, one warp
world each (`num_envs` null), with the same episode keys and files as on the CPU.
"""

from __future__ import annotations

import datetime as dt
import json
import pathlib
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import torch
import yaml
from tqdm import tqdm

from dexbench.data.meta import as_json
from dexbench.envs.dex_env import DexEnv
from dexbench.eval.metrics import summarize
from dexbench.eval.plan import TaskPlan, plan_task
from dexbench.eval.plot import category_chart
from dexbench.eval.records import EpisodeLog, EpisodeRecord
from dexbench.eval.runner import run_episodes
from dexbench.eval.tables import write_tables
from dexbench.eval.video import EpisodeCamera, EpisodeVideos
from dexbench.policies.common.protocol import Policy, check_action_layout
from dexbench.policies.registry import BY_SETTINGS, policy_module
from dexbench.policies.vla_adapters.served import TRANSPORT
from dexbench.tasks.registry import make_env

CHART_FILE = "success_by_category.png"
RUN_FILE = "run.json"
CPU_BATCH = 50  # default envs per task on the cpu backend


def _resolved(value: object) -> object:
    """A setting as a run's identity keeps it: a local folder (a LeRobot policy path) by its
    absolute path, so a resume from another directory still matches."""
    if isinstance(value, str) and pathlib.Path(value).is_dir():
        return str(pathlib.Path(value).resolve())
    return value


class EvalError(ValueError):
    """An evaluation that cannot start or go on as asked."""


@dataclass(frozen=True)
class Video:
    episodes: tuple[int, ...] = ()  # evaluation episode indices filmed in every task
    camera: str = "front"
    width: int = 256
    height: int = 256


@dataclass(frozen=True)
class EvalSpec:
    """An evaluation run, fully resolved."""

    label: str  # the split's name, or the tasks joined by '+'
    groups: dict[str, list[str]]  # category -> tasks
    kind: str  # policy kind
    options: dict[str, Any]  # the kind's settings (conf/policy/<kind>.yaml)
    checkpoint: str | None
    embodiment: str | None
    episodes: int
    seed: int
    horizon: int | None  # control steps per episode; None: the task's time limit
    env: dict[str, Any]  # make_env keyword arguments shared by every task
    settings: dict[str, Any]  # sim, camera, visual, physical as configured (identity)
    num_envs: int | None = None  # None: all pending episodes on warp, else up to 50
    device: str = "auto"
    policy_label: str | None = None
    video: Video = field(default_factory=Video)
    skip_missing: bool = False
    progress: bool = True

    def identity(self) -> dict:
        """What fixes a run's episodes and outcomes: a resumed run must agree on all of
        it (runtime settings such as threads, devices and batch size are left out)."""
        served = ({"policy_settings": {k: _resolved(v) for k, v in self.options.items()
                                       if k not in TRANSPORT}}
                  if self.kind in BY_SETTINGS else {})
        settings = {**self.settings, "sim": {k: v for k, v in self.settings["sim"].items()
                                             if k != "nthread"}}
        ckpt = self.checkpoint
        return {"label": self.label, "categories": self.groups, "policy": self.kind, **served,
                "checkpoint": None if ckpt is None else str(pathlib.Path(ckpt).resolve()),
                "embodiment": self.embodiment, "episodes": self.episodes, "seed": self.seed,
                "horizon": self.horizon, **settings}

    @property
    def backend(self) -> str:
        return str(self.env["backend"])

    def policy_device(self) -> str:
        if self.device == "auto":
            return "cuda" if torch.cuda.is_available() else "cpu"
        return self.device


def check_spec(spec: EvalSpec) -> None:
    """Counts and video episodes in range."""
    if spec.episodes < 1 or (spec.num_envs is not None and spec.num_envs < 1):
        raise EvalError(f"episodes and num_envs must be >= 1, got {spec.episodes} and "
                        f"{spec.num_envs}")
    if spec.horizon is not None and spec.horizon < 1:
        raise EvalError(f"horizon must be >= 1 control steps or null, got {spec.horizon}")
    bad = [e for e in spec.video.episodes if not 0 <= e < spec.episodes]
    if bad:
        raise EvalError(f"video.episodes {bad} lie outside the {spec.episodes} episodes [0, "
                        f"{spec.episodes})")


def plan_tasks(spec: EvalSpec, obs: str | list[str] | None = None
               ) -> tuple[list[TaskPlan], dict[str, str]]:
    """Every task's plan, or an error naming the tasks that cannot run (unless
    `skip_missing`, which returns them as skipped with their reasons). `obs`, when
    given, must be what the policy observes."""
    plans, problems = [], {}
    for category, tasks in spec.groups.items():
        for task in tasks:
            plan = plan_task(task, category, spec.kind, spec.checkpoint, spec.embodiment,
                             spec.options)
            if isinstance(plan, TaskPlan):
                plans.append(plan)
            else:
                problems[task] = plan
    total, rest = sum(map(len, spec.groups.values())), len(plans)
    if problems and (not rest or not spec.skip_missing):
        by_reason: dict[str, list[str]] = {}
        for task, why in problems.items():
            by_reason.setdefault(why, []).append(task)
        listed = "; ".join(f"{', '.join(ts)}: {why}" for why, ts in by_reason.items())
        if total == 1:
            raise EvalError(listed)
        hint = f"; add +skip_missing=true to evaluate the other {rest}" if rest else ""
        raise EvalError(f"{len(problems)} of the {total} tasks of {spec.label} cannot be "
                        f"evaluated ({listed}){hint}")
    if obs is not None:
        for plan in plans:
            wanted = plan.spec.obs if isinstance(plan.spec.obs, str) else list(plan.spec.obs)
            if wanted != obs:
                raise EvalError(f"policy={spec.kind} observes obs={wanted} on {plan.task}, "
                                f"not obs={obs}: the policy fixes its observations; drop obs=")
    return plans, problems


def check_run_dir(spec: EvalSpec, run_dir: pathlib.Path) -> None:
    """An existing run in `run_dir` must be this very run (resume), else an error."""
    run_file = run_dir / RUN_FILE
    if not run_file.exists():
        return
    stored = json.loads(run_file.read_text())["identity"]
    identity = as_json(spec.identity())
    changed = sorted(k for k in {*stored, *identity} if stored.get(k) != identity.get(k))
    if changed:
        raise EvalError(f"{run_dir} holds a run with other settings ({', '.join(changed)}); "
                        "choose another name= or resume= it unchanged")


def open_run(spec: EvalSpec, run_dir: pathlib.Path, config: dict) -> pathlib.Path:
    """Create the run folder's files, or reopen a run whose identity matches."""
    check_run_dir(spec, run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    if not (run_dir / RUN_FILE).exists():
        _write(run_dir / "config.yaml", yaml.safe_dump(config))
        _write(run_dir / RUN_FILE, json.dumps({"identity": spec.identity()}, indent=2) + "\n")
    with open(run_dir / "command.txt", "a") as f:
        f.write(" ".join(sys.argv) + "\n")
    return run_dir


def _write(path: pathlib.Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def log(run_dir: pathlib.Path, line: str) -> None:
    """A timestamped line of `eval.log`."""
    with open(run_dir / "eval.log", "a") as f:
        f.write(f"{dt.datetime.now().isoformat(timespec='seconds')} {line}\n")


def build_env(spec: EvalSpec, plan: TaskPlan, num_envs: int) -> DexEnv:
    """A batched env for `plan` with the policy's observation preset and cameras."""
    obs = plan.spec.obs if isinstance(plan.spec.obs, str) else list(plan.spec.obs)
    kwargs = {**spec.env, "task": plan.task, "embodiment": plan.embodiment, "obs": obs,
              "num_envs": num_envs}
    if plan.spec.cameras is not None:
        kwargs["cameras"] = list(plan.spec.cameras)
    if plan.spec.history is not None:
        kwargs["history"] = plan.spec.history
    env = make_env(**kwargs)
    if spec.horizon is not None:
        env.episode_steps = spec.horizon
    return env


def build_policy(spec: EvalSpec, plan: TaskPlan, env: DexEnv) -> Policy:
    policy = policy_module(spec.kind).build(plan.checkpoint, env, spec.policy_device(),
                                            spec.options)
    check_action_layout(policy.spec, env.embodiment.actuators)
    return policy


def batch_size(spec: EvalSpec, pending: int) -> int:
    """Envs for `pending` episodes: `num_envs` if set, else all of them on warp (one
    world each) and up to `CPU_BATCH` on the cpu backend."""
    if spec.num_envs is not None:
        width = spec.num_envs
    else:
        width = pending if spec.backend == "warp" else min(CPU_BATCH, spec.episodes)
    return max(1, min(width, pending))


def write_results(spec: EvalSpec, run_dir: pathlib.Path, plans: list[TaskPlan],
                  skipped: dict[str, str], records: list[EpisodeRecord]) -> dict:
    """results.{md,csv,tex,json} and the chart from the episodes finished so far."""
    planned = {p.task for p in plans}
    counts = {p.task: 0 for p in plans if p.task not in skipped}
    for r in records:
        if r.task in counts:
            counts[r.task] += 1
    info = {"label": spec.label, "policy": spec.kind,
            "policy_label": spec.policy_label or spec.kind, "checkpoint": spec.checkpoint,
            "episodes_per_task": spec.episodes, "seed": spec.seed, "horizon": spec.horizon,
            "backend": spec.backend, "run_dir": str(run_dir),
            "complete": all(c >= spec.episodes for c in counts.values())}
    summary = summarize(spec.groups, [r for r in records if r.task in planned], skipped, info)
    write_tables(summary, run_dir)
    if summary["categories"]:
        category_chart(summary, run_dir / CHART_FILE)
    return summary


def evaluate(spec: EvalSpec, plans: list[TaskPlan], skipped: dict[str, str],
             run_dir: pathlib.Path,
             on_episode: Callable[[EpisodeRecord], None] | None = None) -> dict:
    """Evaluate every planned task, resuming from `run_dir`'s episodes; the summary.

    `on_episode` sees each record once it is on disk.
    """
    episodes_log = EpisodeLog(run_dir / "episodes.jsonl")
    records = episodes_log.load()
    done = {(r.task, r.episode) for r in records}
    todo = {p.task: [i for i in range(spec.episodes) if (p.task, i) not in done]
            for p in plans}
    total = spec.episodes * len(plans)
    bar = tqdm(total=total, initial=total - sum(map(len, todo.values())), unit="episode",
               disable=not spec.progress)

    def record(rec: EpisodeRecord) -> None:
        episodes_log.append(rec)
        records.append(rec)
        bar.update(1)
        if on_episode is not None:
            on_episode(rec)

    try:
        for plan in plans:
            if todo[plan.task]:
                _evaluate_task(spec, run_dir, plan, todo[plan.task], skipped, record, bar)
                write_results(spec, run_dir, plans, skipped, records)
    except KeyboardInterrupt:
        write_results(spec, run_dir, plans, skipped, records)
        raise
    finally:
        bar.close()
    return write_results(spec, run_dir, plans, skipped, records)


def _videos(spec: EvalSpec, env: DexEnv, run_dir: pathlib.Path,
            task: str) -> EpisodeVideos | None:
    if not spec.video.episodes:
        return None
    try:
        camera = EpisodeCamera(env, spec.video.camera, spec.video.width, spec.video.height)
    except ValueError as err:
        raise EvalError(f"video.camera={spec.video.camera}: {err}") from None
    return EpisodeVideos(camera, set(spec.video.episodes), run_dir / "videos" / task,
                         1.0 / env.control_dt)


def _evaluate_task(spec: EvalSpec, run_dir: pathlib.Path, plan: TaskPlan, pending: list[int],
                   skipped: dict[str, str], record: Callable[[EpisodeRecord], None],
                   bar: tqdm) -> None:
    env = build_env(spec, plan, batch_size(spec, len(pending)))
    try:
        policy = build_policy(spec, plan, env)
    except ValueError as err:
        if not spec.skip_missing:
            others = sum(map(len, spec.groups.values())) > 1
            hint = " (+skip_missing=true evaluates the other tasks)" if others else ""
            raise EvalError(f"{plan.task}: {err}{hint}") from None
        skipped[plan.task] = f"policy cannot run: {err}"
        log(run_dir, f"{plan.task}: skipped: {err}")
        return
    videos = _videos(spec, env, run_dir, plan.task)
    bar.set_description(plan.task)
    log(run_dir, f"{plan.task}: {len(pending)} episodes on {env.num_envs} envs "
                 f"({plan.embodiment}, obs {plan.spec.obs}, {spec.backend} backend)")
    started, successes = time.perf_counter(), 0

    def counted(rec: EpisodeRecord) -> None:
        nonlocal successes
        successes += rec.success
        record(rec)

    try:
        run_episodes(env, policy, pending, spec.seed, counted, videos)
    finally:
        if videos is not None:
            videos.close()
    log(run_dir, f"{plan.task}: {successes}/{len(pending)} successes in "
                 f"{time.perf_counter() - started:.1f} s")


def run(spec: EvalSpec, plans: list[TaskPlan], skipped: dict[str, str],
        run_dir: pathlib.Path) -> tuple[int, dict | None]:
    """Evaluate, logging why a run stopped; (exit status, summary or None)."""
    try:
        summary = evaluate(spec, plans, skipped, run_dir)
    except KeyboardInterrupt:
        log(run_dir, "interrupted")
        return 130, None
    except Exception as err:
        log(run_dir, f"error: {err}" if isinstance(err, ValueError | NotImplementedError)
            else f"stopped by {type(err).__name__}: {err}")
        raise
    return (0 if summary["complete"] else 1), summary

