"""`python eval.py +split=<name> policy=<kind> checkpoint=<path>`: closed-loop evaluation.

Runs `episodes` evaluation episodes per task (keys in `dexbench/eval/seeds.py`, never a
demonstration's) on `num_envs` batched envs with batched policy inference, and writes to
`runs/eval/<split-or-task>/<policy>/<name-or-timestamp>/`: `episodes.jsonl` (one line
per finished episode, as it ends), `results.{md,csv,tex,json}` (per-task success with
95% Wilson intervals, category and overall means), `success_by_category.png`, videos of
`video.episodes` under `videos/<task>/`, `config.yaml`, `run.json` and `eval.log` (per
task, and the error that stopped the run). `resume=<run folder>` (or the same `name=`)
continues an interrupted run: finished episodes are kept and not run again.
`python eval.py task=<Task> policy=expert` evaluates one task. The policy fixes the
observation preset (a checkpoint's own; `state` for the expert): `obs=` may only repeat it.
"""

from __future__ import annotations

import datetime as dt
import json
import pathlib
import sys
import time
from collections.abc import Callable

import torch
import yaml
from omegaconf import DictConfig, OmegaConf
from tqdm import tqdm

from dexbench.cli.config import (
    ConfigError,
    env_kwargs,
    load_config,
    new_run_dir,
    obs_of,
    runs_root,
    write_atomic,
)
from dexbench.cli.errors import USER_ERRORS
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.scene import check_pair
from dexbench.eval.merge import RESULTS_FILE
from dexbench.eval.metrics import summarize
from dexbench.eval.plan import TaskPlan, plan_task
from dexbench.eval.plot import category_chart
from dexbench.eval.records import EpisodeLog, EpisodeRecord
from dexbench.eval.runner import run_episodes
from dexbench.eval.tables import write_tables
from dexbench.eval.throughput import episodes_per_minute, model_module, untrained_checkpoint
from dexbench.eval.video import EpisodeCamera, EpisodeVideos
from dexbench.policies.common.protocol import Policy, PolicySpec, check_action_layout
from dexbench.policies.registry import KINDS, SERVED, WITHOUT_CHECKPOINT, policy_module
from dexbench.policies.vla_adapters.served import TRANSPORT
from dexbench.tasks.registry import TASKS, make_env, task_class

RUNTIME_KEYS = ("num_envs", "device", "progress", "sim.nthread", "skip_missing")
TRAINERS = {"rl": "python rl.py task=<Task>"}  # what writes a kind's checkpoints, if not train.py
CHART_FILE = "success_by_category.png"


class EvalError(ConfigError):
    """An evaluation that cannot start or go on as asked."""


def eval_config(argv: list[str]) -> tuple[DictConfig, pathlib.Path | None]:
    """The resolved config, and the run folder when `resume=` names one."""
    resume = [a.split("=", 1)[1] for a in argv if a.split("=", 1)[0] == "resume"]
    if not resume:
        cfg = load_config("eval", argv)
        if not any(a.lstrip("+").split("=", 1)[0] == "obs" for a in argv):
            cfg.obs = None  # the policy's own preset; an explicit obs= must agree with it
        return cfg, None
    run_dir = pathlib.Path(resume[0])
    if not (run_dir / "config.yaml").exists():
        raise EvalError(f"resume={run_dir} is not an evaluation run folder (no config.yaml)")
    cfg = OmegaConf.create(yaml.safe_load((run_dir / "config.yaml").read_text()))
    cfg.obs = None  # the policy's, as when the run was created
    for arg in argv:
        key, _, value = arg.lstrip("+").partition("=")
        if key == "resume":
            continue
        if key not in RUNTIME_KEYS:
            raise EvalError(f"resume= continues a run with the config stored in it; only "
                            f"{', '.join(RUNTIME_KEYS)} may change (got {key}=)")
        OmegaConf.update(cfg, key, yaml.safe_load(value), force_add=True)
    return cfg, run_dir


def task_groups(cfg: DictConfig) -> tuple[str, dict[str, list[str]]]:
    """(label, category -> tasks): the split's, else those of `tasks` or `task`."""
    split = cfg.get("split")
    if split is not None:
        if not isinstance(split, DictConfig) or "categories" not in split:
            raise EvalError("split must be chosen with +split=<name> (conf/split/)")
        return str(split.name), {str(c): [str(t) for t in ts]
                                 for c, ts in split.categories.items()}
    tasks = [str(t) for t in cfg.tasks] if cfg.get("tasks") else [str(cfg.task)]
    groups: dict[str, list[str]] = {}
    for task in tasks:
        groups.setdefault(TASKS[task].category if task in TASKS else "unknown", []).append(task)
    return "+".join(tasks), groups


def _identity(cfg: DictConfig, label: str, groups: dict[str, list[str]]) -> dict:
    """What fixes a run's episodes and outcomes: a resumed run must agree on all of it."""
    ckpt = cfg.checkpoint
    kind = policy_kind(cfg)
    served = ({"policy_settings": {k: v for k, v in policy_options(cfg).items()
                                   if k not in TRANSPORT}} if kind in SERVED else {})
    return {"label": label, "categories": groups, "policy": kind, **served,
            "checkpoint": None if ckpt is None else str(pathlib.Path(ckpt).resolve()),
            "embodiment": cfg.embodiment, "episodes": int(cfg.episodes),
            "seed": int(cfg.seed), "horizon": cfg.horizon,
            "sim": {k: v for k, v in OmegaConf.to_container(cfg.sim).items() if k != "nthread"},
            **{k: OmegaConf.to_container(cfg[k]) for k in ("camera", "visual", "physical")}}


def _check(cfg: DictConfig) -> None:
    kind = policy_kind(cfg)
    if cfg.checkpoint is None and kind in KINDS and kind not in WITHOUT_CHECKPOINT:
        trainer = TRAINERS.get(kind, f"python train.py policy={kind} task=<Task>")
        raise EvalError(f"policy={kind} needs checkpoint=<a .pt file, a training run folder "
                        f"or a folder of them>; `{trainer}` writes one")
    if cfg.get("obs") is not None:
        obs_of(cfg)
    episodes = int(cfg.episodes)
    if episodes < 1 or (cfg.num_envs is not None and int(cfg.num_envs) < 1):
        raise EvalError(f"episodes and num_envs must be >= 1, got {episodes} and "
                        f"{cfg.num_envs}")
    if cfg.horizon is not None and int(cfg.horizon) < 1:
        raise EvalError(f"horizon must be >= 1 control steps or null, got {cfg.horizon}")
    bad = [e for e in cfg.video.episodes if not 0 <= int(e) < episodes]
    if bad:
        raise EvalError(f"video.episodes {bad} lie outside the {episodes} episodes [0, "
                        f"{episodes})")


def open_run(cfg: DictConfig, run_dir: pathlib.Path | None) -> pathlib.Path:
    """Create the run folder, or reopen one whose identity matches this config."""
    label, groups = task_groups(cfg)
    identity = _identity(cfg, label, groups)
    if run_dir is None:
        name = cfg.name or dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
        run_dir = runs_root() / "eval" / label / policy_kind(cfg) / str(name)
    run_file = run_dir / "run.json"
    if run_file.exists():
        stored = json.loads(run_file.read_text())["identity"]
        changed = sorted(k for k in {*stored, *identity} if stored.get(k) != identity.get(k))
        if changed:
            raise EvalError(f"{run_dir} holds a run with other settings ({', '.join(changed)}"
                            "); choose another name= or resume= it unchanged")
    else:
        run_dir.mkdir(parents=True, exist_ok=True)
        write_atomic(run_dir / "config.yaml", yaml.safe_dump(OmegaConf.to_container(cfg)))
        write_atomic(run_file, json.dumps({"identity": identity}, indent=2) + "\n")
    with open(run_dir / "command.txt", "a") as f:
        f.write(" ".join(sys.argv) + "\n")
    return run_dir


def policy_kind(cfg: DictConfig) -> str:
    """The policy kind: `policy=<kind>` selects conf/policy/<kind>.yaml, named by `name`."""
    return str(cfg.policy.name if isinstance(cfg.policy, DictConfig) else cfg.policy)


def policy_options(cfg: DictConfig) -> dict:
    """The kind's settings from conf/policy/<kind>.yaml (with overrides), for its adapter."""
    if not isinstance(cfg.policy, DictConfig):
        return {}
    options = OmegaConf.to_container(cfg.policy, resolve=True)
    options.pop("name", None)
    return options


def _device(name: str) -> str:
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    return name


def plan_tasks(cfg: DictConfig) -> tuple[list[TaskPlan], dict[str, str]]:
    """Every task's plan, or an error naming the tasks that cannot run (unless
    `+skip_missing=true`, which returns them as skipped with their reasons)."""
    label, groups = task_groups(cfg)
    kind = policy_kind(cfg)
    options = policy_options(cfg)
    plans, problems = [], {}
    for category, tasks in groups.items():
        for task in tasks:
            plan = plan_task(task, category, kind, cfg.checkpoint, cfg.embodiment, options)
            if isinstance(plan, TaskPlan):
                plans.append(plan)
            else:
                problems[task] = plan
    total, rest = sum(map(len, groups.values())), len(plans)
    if problems and (not rest or not cfg.get("skip_missing", False)):
        by_reason: dict[str, list[str]] = {}
        for task, why in problems.items():
            by_reason.setdefault(why, []).append(task)
        listed = "; ".join(f"{', '.join(ts)}: {why}" for why, ts in by_reason.items())
        if total == 1:
            raise EvalError(listed)
        hint = f"; add +skip_missing=true to evaluate the other {rest}" if rest else ""
        raise EvalError(f"{len(problems)} of the {total} tasks of {label} cannot be "
                        f"evaluated ({listed}){hint}")
    _check_obs(cfg, plans)
    return plans, problems


def _check_obs(cfg: DictConfig, plans: list[TaskPlan]) -> None:
    """The policy fixes what it observes: an explicit `obs=` may only repeat it."""
    if cfg.get("obs") is None:
        return
    obs = obs_of(cfg)
    for plan in plans:
        wanted = plan.spec.obs if isinstance(plan.spec.obs, str) else list(plan.spec.obs)
        if wanted != obs:
            raise EvalError(f"policy={policy_kind(cfg)} observes obs={wanted} on {plan.task}, "
                            f"not obs={cfg.obs}: the policy fixes its observations; drop obs=")


def build_env(cfg: DictConfig, plan: TaskPlan, num_envs: int) -> DexEnv:
    """A batched env for `plan` with the policy's observation preset."""
    obs = plan.spec.obs if isinstance(plan.spec.obs, str) else list(plan.spec.obs)
    kwargs = env_kwargs(OmegaConf.merge(cfg, {"num_envs": num_envs, "obs": obs}))
    kwargs.update(task=plan.task, embodiment=plan.embodiment)
    if plan.spec.cameras is not None:
        kwargs.update(cameras=list(plan.spec.cameras))
    env = make_env(**kwargs)
    if cfg.horizon is not None:
        env.episode_steps = int(cfg.horizon)
    return env


def build_policy(cfg: DictConfig, plan: TaskPlan, env: DexEnv) -> Policy:
    policy = policy_module(policy_kind(cfg)).build(plan.checkpoint, env, _device(cfg.device),
                                                   policy_options(cfg))
    check_action_layout(policy.spec, env.embodiment.actuators)
    return policy


def _log(run_dir: pathlib.Path, line: str) -> None:
    with open(run_dir / "eval.log", "a") as f:
        f.write(f"{dt.datetime.now().isoformat(timespec='seconds')} {line}\n")


def write_results(cfg: DictConfig, run_dir: pathlib.Path, plans: list[TaskPlan],
                  skipped: dict[str, str], records: list[EpisodeRecord]) -> dict:
    """results.{md,csv,tex,json} and the chart from the episodes finished so far."""
    label, groups = task_groups(cfg)
    planned = {p.task for p in plans}
    counts = {p.task: 0 for p in plans if p.task not in skipped}
    for r in records:
        if r.task in planned:
            counts[r.task] += 1
    kind = policy_kind(cfg)
    info = {"label": label, "policy": kind, "policy_label": cfg.label or kind,
            "checkpoint": cfg.checkpoint, "episodes_per_task": int(cfg.episodes),
            "seed": int(cfg.seed), "horizon": cfg.horizon, "run_dir": str(run_dir),
            "complete": all(c >= int(cfg.episodes) for c in counts.values())}
    summary = summarize(groups, [r for r in records if r.task in planned], skipped, info)
    write_tables(summary, run_dir)
    if summary["categories"]:
        category_chart(summary, run_dir / CHART_FILE)
    return summary


def prepare(cfg: DictConfig, resume: pathlib.Path | None = None
            ) -> tuple[list[TaskPlan], dict[str, str], pathlib.Path]:
    """Check the config and every task, then create or reopen the run folder."""
    _check(cfg)
    plans, skipped = plan_tasks(cfg)
    return plans, skipped, open_run(cfg, resume)


def evaluate(cfg: DictConfig, plans: list[TaskPlan], skipped: dict[str, str],
             run_dir: pathlib.Path,
             on_episode: Callable[[EpisodeRecord], None] | None = None) -> dict:
    """Evaluate every planned task, resuming from `run_dir`'s episodes; the summary.

    `on_episode` sees each record once it is on disk.
    """
    log = EpisodeLog(run_dir / "episodes.jsonl")
    records = log.load()
    episodes = int(cfg.episodes)
    done = {(r.task, r.episode) for r in records}
    todo = {p.task: [i for i in range(episodes) if (p.task, i) not in done] for p in plans}
    bar = tqdm(total=episodes * len(plans), initial=episodes * len(plans) - sum(
        map(len, todo.values())), unit="episode", disable=not cfg.progress)

    def record(rec: EpisodeRecord) -> None:
        log.append(rec)
        records.append(rec)
        bar.update(1)
        if on_episode is not None:
            on_episode(rec)

    try:
        for plan in plans:
            if todo[plan.task]:
                _evaluate_task(cfg, run_dir, plan, todo[plan.task], skipped, record, bar)
                write_results(cfg, run_dir, plans, skipped, records)
    except KeyboardInterrupt:
        write_results(cfg, run_dir, plans, skipped, records)
        raise
    finally:
        bar.close()
    return write_results(cfg, run_dir, plans, skipped, records)


def _evaluate_task(cfg: DictConfig, run_dir: pathlib.Path, plan: TaskPlan, pending: list[int],
                   skipped: dict[str, str], record: Callable[[EpisodeRecord], None],
                   bar: tqdm) -> None:
    width = int(cfg.num_envs) if cfg.num_envs is not None else min(50, int(cfg.episodes))
    env = build_env(cfg, plan, min(width, len(pending)))
    try:
        policy = build_policy(cfg, plan, env)
    except ValueError as err:
        if not cfg.get("skip_missing", False):
            others = sum(map(len, task_groups(cfg)[1].values())) > 1
            hint = " (+skip_missing=true evaluates the other tasks)" if others else ""
            raise EvalError(f"{plan.task}: {err}{hint}") from None
        skipped[plan.task] = f"policy cannot run: {err}"
        _log(run_dir, f"{plan.task}: skipped: {err}")
        return
    videos = None
    if cfg.video.episodes:
        try:
            camera = EpisodeCamera(env, str(cfg.video.camera), int(cfg.video.width),
                                   int(cfg.video.height))
        except ValueError as err:
            raise EvalError(f"video.camera={cfg.video.camera}: {err}") from None
        videos = EpisodeVideos(camera, {int(e) for e in cfg.video.episodes},
                               run_dir / "videos" / plan.task, 1.0 / env.control_dt)
    bar.set_description(plan.task)
    _log(run_dir, f"{plan.task}: {len(pending)} episodes on {env.num_envs} envs "
                  f"({plan.embodiment}, obs {plan.spec.obs})")
    started, successes = time.perf_counter(), 0

    def counted(rec: EpisodeRecord) -> None:
        nonlocal successes
        successes += rec.success
        record(rec)

    try:
        run_episodes(env, policy, pending, int(cfg.seed), counted, videos)
    finally:
        if videos is not None:
            videos.close()
    _log(run_dir, f"{plan.task}: {successes}/{len(pending)} successes in "
                  f"{time.perf_counter() - started:.1f} s")


def main(argv: list[str]) -> int:
    cfg, resume = eval_config(argv)
    plans, skipped, run_dir = prepare(cfg, resume)
    try:
        summary = evaluate(cfg, plans, skipped, run_dir)
    except KeyboardInterrupt:
        _log(run_dir, "interrupted")
        print(f"\ninterrupted: finished episodes are kept in {run_dir}/episodes.jsonl; "
              f"continue with `python eval.py resume={run_dir}`", file=sys.stderr)
        return 130
    except USER_ERRORS as err:
        _log(run_dir, f"error: {err}")
        raise
    except Exception as err:
        _log(run_dir, f"stopped by {type(err).__name__}: {err}")
        raise
    print((run_dir / "results.md").read_text())
    print(json.dumps({"overall": summary["overall"], "episodes": summary["episodes"],
                      "complete": summary["complete"], "run_dir": str(run_dir),
                      "results": str(run_dir / RESULTS_FILE)}))
    return 0 if summary["complete"] else 1


def bench_eval(argv: list[str]) -> dict:
    """`python bench.py eval`: episodes/min of `num_envs` batched envs against one env at
    a time, same policy and horizon; a JSON-ready result."""
    cfg = load_config("bench_eval", argv)
    kind = policy_kind(cfg)
    n, episodes, sequential = int(cfg.num_envs), int(cfg.episodes), int(cfg.sequential_episodes)
    if min(n, episodes, sequential, int(cfg.horizon)) < 1:
        raise EvalError("num_envs, episodes, sequential_episodes and horizon must be >= 1")
    task = str(cfg.task)
    embodiment = cfg.embodiment or task_class(task).default_embodiment
    check_pair(TASKS[task], embodiment)
    run_dir = new_run_dir("bench", f"eval-{kind}-{cfg.task}", cfg)
    checkpoint = cfg.checkpoint
    if checkpoint is None and kind not in WITHOUT_CHECKPOINT:
        try:
            spec = PolicySpec(obs=model_module(kind).OBS)
        except ValueError as err:
            raise EvalError(str(err)) from None
        probe = build_env(cfg, TaskPlan(task, "", embodiment, None, spec), 2)
        checkpoint = str(untrained_checkpoint(kind, OmegaConf.to_container(cfg.policy), probe,
                                              run_dir / "untrained.pt"))
    plan = plan_task(str(cfg.task), "", kind, checkpoint, cfg.embodiment, policy_options(cfg))
    if not isinstance(plan, TaskPlan):
        raise EvalError(f"{cfg.task}: {plan}")
    rates = {}
    for label, width, count in (("batched", n, episodes), ("sequential", 1, sequential)):
        env = build_env(cfg, plan, width)
        policy = build_policy(cfg, plan, env)
        bar = tqdm(total=count, desc=f"{label} x{width}", unit="episode",
                   disable=not cfg.progress, leave=False)
        with bar:
            rates[label] = episodes_per_minute(env, policy, count, int(cfg.seed),
                                               lambda _, bar=bar: bar.update(1))
        print(f"{label}: {rates[label]:,.1f} episodes/min ({width} env(s), {count} "
              f"episodes of up to {cfg.horizon} steps)")
    result = {"benchmark": "eval", "task": plan.task, "embodiment": plan.embodiment,
              "policy": kind, "checkpoint": checkpoint, "num_envs": n, "horizon": int(
                  cfg.horizon), "batched_episodes": episodes, "sequential_episodes": sequential,
              "device": _device(cfg.device), "torch_threads": torch.get_num_threads(),
              "batched_eps_per_min": round(rates["batched"], 2),
              "sequential_eps_per_min": round(rates["sequential"], 2),
              "ratio": round(rates["batched"] / rates["sequential"], 2),
              "run_dir": str(run_dir)}
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    return result
