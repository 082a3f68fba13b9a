"""`python eval.py +split=<name> policy=<kind> checkpoint=<path>`: closed-loop evaluation.

Runs `episodes` evaluation episodes per task (keys in `dexbench/eval/seeds.py`, never a
demonstration's) on batched envs with batched policy inference, and writes to
`runs/eval/<split-or-task>/<policy>/<name-or-timestamp>/`: `episodes.jsonl` (one line
per finished episode, as it ends), `results.{md,csv,tex,json}` (per-task success with
95% Wilson intervals, category and overall means), `success_by_category.png`, videos of
`video.episodes` under `videos/<task>/`, `config.yaml`, `run.json`, `eval.log` (per
task, and the error that stopped the run) and Hydra's `.hydra/`. `resume=<run folder>`
(or the same `name=`) continues an interrupted run: finished episodes are kept and not
run again. `python eval.py task=<Task> policy=expert` evaluates one task;
`sim.backend=warp` runs each task's episodes as warp worlds (GPU). The policy fixes the
observation preset (a checkpoint's own; `state` for the expert): `obs=` may only repeat
it. With `-m`, each job is one run; `+split=<name> split_task=A,B,...` sweeps a split's
tasks as separate jobs (`python -m dexbench split <name>` prints them) and
`python -m dexbench merge <sweep folder>` joins their results. `wandb.enabled=true`
(conf/wandb/: offline by default, under `wandb/` in the run folder) logs the finished
run's table, chart, videos and overall success to W&B. The logic lives in
`dexbench/eval/session.py`; this module turns a config into an `EvalSpec`.
"""

from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass, replace

import torch
import yaml
from omegaconf import DictConfig, ListConfig, OmegaConf
from tqdm import tqdm

from dexbench.cli.app import Command, hydra_main, register, stamp
from dexbench.cli.config import (
    env_kwargs,
    job_device,
    load_config,
    obs_of,
    open_run_dir,
    runs_root,
    write_atomic,
)
from dexbench.envs.scene import check_pair
from dexbench.eval.merge import RESULTS_FILE
from dexbench.eval.plan import TaskPlan, plan_task
from dexbench.eval.session import (
    CHART_FILE,
    EvalError,
    EvalSpec,
    Video,
    build_env,
    build_policy,
    check_run_dir,
    check_spec,
    evaluate,
    open_run,
    plan_tasks,
)
from dexbench.eval.session import run as run_eval
from dexbench.eval.tables import CSV_COLUMNS
from dexbench.eval.throughput import episodes_per_minute, model_module, untrained_checkpoint
from dexbench.policies.common.protocol import PolicySpec
from dexbench.policies.common.run_log import finish_wandb, start_wandb, wandb_missing
from dexbench.policies.registry import KINDS, WITHOUT_CHECKPOINT
from dexbench.tasks.registry import TASKS, task_class

RUNTIME_KEYS = ("num_envs", "device", "progress", "sim.nthread", "skip_missing",
                "wandb.enabled", "wandb.mode", "wandb.project")
TRAINERS = {"rl": "python rl.py task=<Task>"}  # what writes a kind's checkpoints, if not train.py

__all__ = ["EvalError", "bench_eval", "eval_config", "evaluate", "main", "plan_tasks",
           "prepare", "spec_of"]


@dataclass(frozen=True)
class Prepared:
    """A checked evaluation: its config (a resumed run's own), spec and plans."""

    cfg: DictConfig
    spec: EvalSpec
    plans: list[TaskPlan]
    skipped: dict[str, str]


def eval_config(cfg: DictConfig, overrides: list[str]) -> DictConfig:
    """The config to run: `cfg`, or with `resume=` the run's stored config with the
    runtime settings among `overrides` applied."""
    if not cfg.get("resume"):
        return cfg
    run_dir = pathlib.Path(cfg.resume)
    if not (run_dir / "config.yaml").exists():
        raise EvalError(f"resume={run_dir} is not an evaluation run folder (no config.yaml)")
    stored = OmegaConf.create(yaml.safe_load((run_dir / "config.yaml").read_text()))
    stored.obs = None  # the policy's, as when the run was created
    stored.resume = str(run_dir)
    for arg in overrides:
        key, _, value = arg.lstrip("+").partition("=")
        if key == "resume":
            continue
        if key not in RUNTIME_KEYS:
            raise EvalError(f"resume= continues a run with the config stored in it; only "
                            f"{', '.join(RUNTIME_KEYS)} may change (got {key}=)")
        OmegaConf.update(stored, key, yaml.safe_load(value), force_add=True)
    return stored


def task_groups(cfg: DictConfig) -> tuple[str, dict[str, list[str]]]:
    """(label, category -> tasks): the split's (or its `split_task` alone), else those
    of `tasks` or `task`."""
    split = cfg.get("split")
    if split is not None:
        if not isinstance(split, DictConfig) or "categories" not in split:
            raise EvalError("split must be chosen with +split=<name> (conf/split/)")
        groups = {str(c): [str(t) for t in ts] for c, ts in split.categories.items()}
        only = cfg.get("split_task")
        if only is not None:
            groups = {c: [t for t in ts if t == only] for c, ts in groups.items()}
            groups = {c: ts for c, ts in groups.items() if ts}
            if not groups:
                raise EvalError(f"split_task={only} is not a task of split {split.name}; "
                                f"`python -m dexbench split {split.name}` lists them")
        return str(split.name), groups
    tasks = [str(t) for t in cfg.tasks] if cfg.get("tasks") else [str(cfg.task)]
    groups: dict[str, list[str]] = {}
    for task in tasks:
        groups.setdefault(TASKS[task].category if task in TASKS else "unknown", []).append(task)
    return "+".join(tasks), groups


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


def spec_of(cfg: DictConfig, untrained: bool = False) -> EvalSpec:
    """The run `cfg` asks for, with its values checked (`untrained`: a kind that needs a
    checkpoint may go without, as `bench.py eval` times one)."""
    kind = policy_kind(cfg)
    if (cfg.checkpoint is None and kind in KINDS and kind not in WITHOUT_CHECKPOINT
            and not untrained):
        trainer = TRAINERS.get(kind, f"python train.py policy={kind} task=<Task>")
        raise EvalError(f"policy={kind} needs checkpoint=<a .pt file, a training run folder "
                        f"or a folder of them>; `{trainer}` writes one")
    if cfg.get("obs") is not None:
        obs_of(cfg)
    label, groups = task_groups(cfg)
    video = cfg.get("video") or {"episodes": [], "camera": "front", "width": 256,
                                 "height": 256}
    settings = {k: OmegaConf.to_container(cfg[k], resolve=True)
                for k in ("sim", "camera", "visual", "physical")}
    spec = EvalSpec(
        label=label, groups=groups, kind=kind, options=policy_options(cfg),
        checkpoint=None if cfg.checkpoint is None else str(cfg.checkpoint),
        embodiment=cfg.embodiment, episodes=int(cfg.episodes), seed=int(cfg.seed),
        horizon=None if cfg.horizon is None else int(cfg.horizon),
        env=env_kwargs(OmegaConf.merge(cfg, {"obs": "state", "num_envs": 1})),
        settings=settings, num_envs=None if cfg.num_envs is None else int(cfg.num_envs),
        device=job_device(str(cfg.device)), policy_label=cfg.get("label"),
        video=Video(tuple(int(e) for e in video["episodes"]), str(video["camera"]),
                    int(video["width"]), int(video["height"])),
        skip_missing=bool(cfg.get("skip_missing", False)), progress=bool(cfg.progress))
    check_spec(spec)
    return spec


def _obs(cfg: DictConfig) -> str | list[str] | None:
    if cfg.get("obs") is None:
        return None
    return list(cfg.obs) if isinstance(cfg.obs, ListConfig) else str(cfg.obs)


def run_dir(cfg: DictConfig) -> tuple[str, str]:
    """`eval/<label>/<policy>` and the run's name (a resumed run: its own folder)."""
    if cfg.get("resume"):
        return str(pathlib.Path(cfg.resume).resolve()), ""
    try:
        label = task_groups(cfg)[0]
    except (EvalError, KeyError):
        label = "eval"
    return f"eval/{label}/{policy_kind(cfg)}", str(cfg.name or "{stamp}")


def check(cfg: DictConfig, overrides: list[str]) -> Prepared:
    """Everything that can be wrong, before the run folder exists; a named or resumed run
    must match what it holds."""
    cfg = eval_config(cfg, overrides)
    missing = wandb_missing(_wandb(cfg))
    if missing:
        raise EvalError(missing)
    spec = spec_of(cfg)
    plans, skipped = plan_tasks(spec, _obs(cfg))
    layout, leaf = run_dir(cfg)
    if "{stamp}" not in leaf:
        check_run_dir(spec, runs_root() / layout / leaf)
    return Prepared(cfg, spec, plans, skipped)


def prepare(argv: list[str]) -> tuple[Prepared, pathlib.Path]:
    """Programmatic: the checked run and its opened folder (tests, notebooks)."""
    cfg = load_config("eval", argv)
    prepared = check(cfg, argv)
    folder = COMMAND.folder(prepared.cfg, stamp())
    return prepared, open_run(prepared.spec, folder, _config(prepared.cfg))


def _config(cfg: DictConfig) -> dict:
    return OmegaConf.to_container(cfg, resolve=True)


def _wandb(cfg: DictConfig) -> dict | None:
    """The `wandb:` block (a run stored before it existed has none)."""
    block = cfg.get("wandb")
    return None if block is None else OmegaConf.to_container(block, resolve=True)


def log_wandb(cfg: DictConfig, run_dir: pathlib.Path, summary: dict) -> None:
    """A finished run to W&B, when `wandb.enabled`: the results table, the category chart,
    the episode videos and the overall success (its summary)."""
    run = start_wandb(run_dir, _config(cfg), _wandb(cfg), "eval")
    if run is None:
        return
    import wandb

    rows = [[t[c] for c in CSV_COLUMNS] for t in summary["tasks"]]
    media: dict = {"eval/results": wandb.Table(columns=list(CSV_COLUMNS), data=rows)}
    if (run_dir / CHART_FILE).exists():
        media["eval/success_by_category"] = wandb.Image(str(run_dir / CHART_FILE))
    for video in sorted(run_dir.glob("videos/*/*.mp4")):
        media[f"eval/videos/{video.parent.name}/{video.stem}"] = wandb.Video(str(video))
    run.log(media)
    finish_wandb(run, {"overall_success": summary["overall"], "episodes": summary["episodes"],
                       **{f"success/{t['task']}": t["success_rate"] for t in summary["tasks"]}})


def run(cfg: DictConfig, prepared: Prepared, out: pathlib.Path) -> int:
    spec = prepared.spec
    run_dir = open_run(spec, out, _config(prepared.cfg))
    code, summary = run_eval(spec, prepared.plans, prepared.skipped, run_dir)
    if summary is None:
        print(f"\ninterrupted: finished episodes are kept in {run_dir}/episodes.jsonl; "
              f"continue with `python eval.py resume={run_dir}`")
        return code
    log_wandb(prepared.cfg, run_dir, summary)
    print((run_dir / "results.md").read_text())
    print(json.dumps({"overall": summary["overall"], "episodes": summary["episodes"],
                      "complete": summary["complete"], "run_dir": str(run_dir),
                      "results": str(run_dir / RESULTS_FILE)}))
    return code


COMMAND = register(Command("eval", run, check, run_dir))
main = COMMAND.main
hydra_entry = hydra_main(COMMAND)


def bench_backends(cfg: DictConfig) -> list[str]:
    backends = [str(b) for b in cfg.backends]
    unknown = sorted(set(backends) - {"cpu", "warp"})
    if unknown or not backends:
        raise EvalError(f"backends={backends}: choose from cpu and warp, e.g. "
                        "backends=[cpu,warp]")
    return backends


def bench_check(cfg: DictConfig, overrides: list[str]) -> EvalSpec:
    """`bench.py eval`'s settings, checked before its run folder exists."""
    kind = policy_kind(cfg)
    counts = (int(cfg.num_envs), int(cfg.episodes), int(cfg.sequential_episodes),
              int(cfg.horizon))
    if min(counts) < 1 or (cfg.warp_episodes is not None and int(cfg.warp_episodes) < 1):
        raise EvalError("num_envs, episodes, sequential_episodes, warp_episodes and horizon "
                        "must be >= 1")
    bench_backends(cfg)
    task = str(cfg.task)
    embodiment = cfg.embodiment or task_class(task).default_embodiment
    check_pair(TASKS[task], embodiment)
    if cfg.checkpoint is None and kind not in WITHOUT_CHECKPOINT:
        try:
            model_module(kind)
        except ValueError as err:
            raise EvalError(str(err)) from None
    merged = OmegaConf.merge(cfg, {"episodes": max(counts[1], counts[2])})
    return replace(spec_of(merged, untrained=True),
                   embodiment=embodiment, num_envs=int(cfg.num_envs))


def _rate(spec: EvalSpec, plan: TaskPlan, label: str, width: int, count: int,
          progress: bool) -> float:
    env = build_env(spec, plan, width)
    policy = build_policy(spec, plan, env)
    bar = tqdm(total=count, desc=f"{label} x{width}", unit="episode", disable=not progress,
               leave=False)
    with bar:
        rate = episodes_per_minute(env, policy, count, spec.seed,
                                   lambda _, bar=bar: bar.update(1))
    print(f"{label}: {rate:,.1f} episodes/min ({width} env(s), {count} episodes of up to "
          f"{spec.horizon} steps)")
    return rate


def bench_run(cfg: DictConfig, spec: EvalSpec, out: pathlib.Path) -> dict:
    """Episodes/min of `num_envs` batched cpu envs against one env at a time, and on the
    warp backend (`backends=[cpu,warp]`) with every episode a warp world; a JSON-ready
    result written to `metrics.json`."""
    kind, task = spec.kind, str(cfg.task)
    run_dir = open_run_dir(out, cfg)
    checkpoint = spec.checkpoint
    if checkpoint is None and kind not in WITHOUT_CHECKPOINT:
        probe_plan = TaskPlan(task, "", spec.embodiment, None,
                              PolicySpec(obs=model_module(kind).OBS))
        probe = build_env(spec, probe_plan, 2)
        checkpoint = str(untrained_checkpoint(kind, OmegaConf.to_container(cfg.policy), probe,
                                              run_dir / "untrained.pt"))
    plan = plan_task(task, "", kind, checkpoint, cfg.embodiment, spec.options)
    if not isinstance(plan, TaskPlan):
        raise EvalError(f"{task}: {plan}")
    progress = bool(cfg.progress)
    rates, n, episodes = {}, int(cfg.num_envs), int(cfg.episodes)
    for backend in bench_backends(cfg):
        on = replace(spec, env={**spec.env, "backend": backend,
                                "renderer": "warp" if backend == "warp" else "cpu"})
        if backend == "warp":
            count = int(cfg.warp_episodes or episodes)
            rates["warp"] = _rate(on, plan, "warp", count, count, progress)
        else:
            rates["batched"] = _rate(on, plan, "batched", n, episodes, progress)
            rates["sequential"] = _rate(on, plan, "sequential", 1,
                                        int(cfg.sequential_episodes), progress)
    result = {"benchmark": "eval", "task": plan.task, "embodiment": plan.embodiment,
              "policy": kind, "checkpoint": checkpoint, "num_envs": n,
              "horizon": int(cfg.horizon), "batched_episodes": episodes,
              "sequential_episodes": int(cfg.sequential_episodes),
              "device": spec.policy_device(), "torch_threads": torch.get_num_threads(),
              **{f"{k}_eps_per_min": round(v, 2) for k, v in rates.items()},
              "run_dir": str(run_dir)}
    if "batched" in rates:
        result["ratio"] = round(rates["batched"] / rates["sequential"], 2)
    if "warp" in rates:
        result["warp_episodes"] = int(cfg.warp_episodes or episodes)
        result["gpu"] = torch.cuda.get_device_name(0) if torch.cuda.is_available() else None
        if "batched" in rates:
            result["warp_vs_cpu"] = round(rates["warp"] / rates["batched"], 2)
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    return result


def bench_eval(argv: list[str]) -> dict:
    """Programmatic `python bench.py eval key=value ...`."""
    cfg = load_config("bench_eval", argv)
    spec = bench_check(cfg, argv)
    return bench_run(cfg, spec, BENCH_EVAL.folder(cfg, stamp()))


def _bench_dir(cfg: DictConfig) -> tuple[str, str]:
    return "bench", f"{{stamp}}-eval-{policy_kind(cfg)}-{cfg.task}"


def _bench_print(cfg: DictConfig, spec: EvalSpec, out: pathlib.Path) -> int:
    print(json.dumps(bench_run(cfg, spec, out)))
    return 0


BENCH_EVAL = register(Command("bench_eval", _bench_print, bench_check, _bench_dir))
