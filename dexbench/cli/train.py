"""`python train.py policy=dp|dp3 task=<T> [embodiment=<E>] ...`: train a policy.

Reads the demonstrations `python collect.py task=<T> embodiment=<E>` wrote (or
`dataset=<folder>`); DP3 first replays them to the `pointcloud` preset (once: the replay
is kept beside the dataset). Writes `best.pt`/`last.pt`, the resolved config,
`metrics.csv`, TensorBoard logs and `summary.json` under
`runs/train/<task>/<embodiment>/<policy>/<timestamp>-seed<seed>/` (a sweep, `-m
policy=dp,dp3 task=A,B`: `runs/train/multirun/<time>/<task>/<embodiment>/<policy>/<job>/`,
the layout `eval.py checkpoint=<folder>` reads per task).
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import pathlib
import sys
from collections.abc import Iterable
from dataclasses import dataclass
from types import ModuleType

import torch
from omegaconf import DictConfig, OmegaConf

from dexbench.cli.app import Command, hydra_main, register
from dexbench.cli.config import (
    ConfigError,
    dataset_path,
    default_embodiment,
    env_kwargs,
    job_device,
    open_run_dir,
)
from dexbench.data.files import write_json
from dexbench.data.meta import DatasetError, read_meta
from dexbench.envs.scene import check_pair
from dexbench.policies.common.checkpoint import save_checkpoint
from dexbench.policies.common.demos import Demos, available_groups, load_demos
from dexbench.policies.common.run_log import RunLog
from dexbench.policies.common.runner import resolve_device
from dexbench.policies.common.training import TrainSettings, fit_normalizer, train_policy
from dexbench.tasks.registry import task_class

MODELS = {"dp": "dexbench.policies.dp.model", "dp3": "dexbench.policies.dp3.model"}


def model_module(name: str) -> ModuleType:
    if name not in MODELS:
        raise ConfigError(f"policy={name} cannot be trained here; trainable: {sorted(MODELS)}")
    return importlib.import_module(MODELS[name])


def source_dataset(cfg: DictConfig) -> pathlib.Path:
    """The demonstrations to train on, or an error saying how to make them."""
    if cfg.dataset:
        path = pathlib.Path(cfg.dataset)
        if not path.exists():
            raise DatasetError(f"dataset={path} does not exist")
        return path
    embodiment = cfg.embodiment or task_class(cfg.task).default_embodiment
    path = dataset_path(cfg.task, embodiment, cfg.dataset_name)
    if not path.exists():
        raise DatasetError(
            f"no demonstrations at {path}; collect them first with `python collect.py "
            f"task={cfg.task} embodiment={embodiment} num_demos=50` (or pass dataset=<folder>)")
    return path


def chosen_groups(cfg: DictConfig, model: ModuleType, available: Iterable[str]) -> list[str]:
    """The policy's input groups from those available: all it can use, or only
    `policy.groups` where given (e.g. without `policy`, the previous action, which a
    policy can learn to repeat instead of acting)."""
    groups = model.input_groups(available)
    wanted = cfg.policy.get("groups")
    if wanted is None:
        return groups
    unknown = sorted(set(wanted) - set(groups))
    if unknown:
        raise ConfigError(f"policy.groups={list(wanted)}: {unknown} not among this policy's "
                          f"inputs in the data {groups}")
    return model.input_groups([g for g in groups if g in set(wanted)])


def training_data(cfg: DictConfig, model: ModuleType) -> Demos:
    """The dataset as arrays, replayed to the policy's observation preset when needed."""
    root = source_dataset(cfg)
    if root.suffix == ".npz":
        demos = Demos.load(root)
        demos.obs = {g: demos.obs[g] for g in chosen_groups(cfg, model, demos.obs)}
        return demos
    try:
        groups = chosen_groups(cfg, model, available_groups(root))
    except ValueError:
        if model.OBS == "state":
            raise
        # Replay renders through LeRobot's writer: imported only when a replay is due,
        # so training from existing replays needs neither.
        from dexbench.cli.replay import FROM_DATASET
        from dexbench.data.replay import default_out, replay_states

        replayed = default_out(root, model.OBS)
        if not replayed.exists():
            print(f"replaying {root} to obs={model.OBS} -> {replayed}", file=sys.stderr)
            settings = {k: v for k, v in env_kwargs(cfg).items() if k not in FROM_DATASET}
            replay_states(root, replayed, model.OBS, num_envs=int(cfg.num_envs),
                          progress=bool(cfg.progress), **settings)
        root = replayed
        groups = chosen_groups(cfg, model, available_groups(root))
    return load_demos(root, groups)


def settings_of(cfg: DictConfig) -> TrainSettings:
    pol, tr = cfg.policy, cfg.train
    epochs = int(tr.epochs if tr.epochs is not None else pol.epochs)
    if epochs < 1 or (tr.max_steps is not None and int(tr.max_steps) < 1):
        raise ConfigError(f"need train.epochs >= 1 and train.max_steps >= 1, got {epochs}, "
                          f"{tr.max_steps}")
    return TrainSettings(
        epochs=epochs, batch_size=int(pol.optim.batch_size), lr=float(pol.optim.lr),
        weight_decay=float(pol.optim.weight_decay), betas=tuple(pol.optim.betas),
        grad_clip=float(pol.optim.grad_clip), warmup_steps=int(pol.optim.warmup_steps),
        ema_max_decay=float(pol.ema.max_decay), ema_power=float(pol.ema.power),
        n_obs_steps=int(pol.n_obs_steps), horizon=int(pol.horizon),
        val_fraction=float(tr.val_fraction),
        patience=None if pol.patience is None else int(pol.patience),
        max_steps=None if tr.max_steps is None else int(tr.max_steps),
        max_minutes=None if tr.max_minutes is None else float(tr.max_minutes),
        save_every=int(tr.save_every), seed=int(cfg.seed), amp=bool(tr.amp),
        progress=bool(cfg.progress))


@dataclass
class Prepared:
    cfg: DictConfig  # with the dataset's embodiment and the epochs filled in
    model: ModuleType
    settings: TrainSettings
    device: torch.device
    demos: Demos


def _same_pair(cfg: DictConfig, meta: dict, source: object) -> None:
    if cfg.task != meta["task"] or (cfg.embodiment and cfg.embodiment != meta["embodiment"]):
        raise ConfigError(f"{source} holds {meta['task']} on {meta['embodiment']}; pass "
                          f"task={meta['task']} embodiment={meta['embodiment']}")


def validate(cfg: DictConfig, overrides: list[str]) -> tuple[ModuleType, TrainSettings,
                                                              torch.device]:
    """Policy, settings, device and the dataset's task and embodiment, without loading
    the demonstrations: cheap enough for a sweep to test every job up front, leaving the
    loading (and a DP3 replay) to the jobs, in parallel."""
    model_mod = model_module(cfg.policy.name)
    if cfg.embodiment:  # before looking for demonstrations that could never exist
        check_pair(task_class(cfg.task), cfg.embodiment)
    settings = settings_of(cfg)
    if cfg.wandb.enabled and importlib.util.find_spec("wandb") is None:
        raise ConfigError("wandb.enabled=true needs `pip install wandb`")
    try:
        device = resolve_device(job_device(str(cfg.device)))
    except (ValueError, RuntimeError) as err:
        raise ConfigError(f"device={cfg.device}: {err}") from None
    root = source_dataset(cfg)
    if root.is_dir():
        _same_pair(cfg, read_meta(root), root)
    return model_mod, settings, device


def check(cfg: DictConfig, overrides: list[str]) -> Prepared:
    """Settings, device and the demonstrations (checksums verified, replayed to the
    policy's observations when needed), before the run folder exists."""
    model_mod, settings, device = validate(cfg, overrides)
    demos = training_data(cfg, model_mod)
    meta = demos.meta
    _same_pair(cfg, meta, demos.source)
    cfg = OmegaConf.merge(cfg, {"embodiment": meta["embodiment"],
                                "dataset": demos.source, "train": {"epochs": settings.epochs}})
    return Prepared(cfg, model_mod, settings, device, demos)


def run_dir(cfg: DictConfig) -> tuple[str, str]:
    """`train/<task>/<embodiment>/<policy>`, the embodiment the dataset's when not given."""
    embodiment = cfg.embodiment
    if not embodiment and cfg.dataset and pathlib.Path(str(cfg.dataset)).is_dir():
        try:
            embodiment = read_meta(pathlib.Path(str(cfg.dataset)))["embodiment"]
        except DatasetError:
            embodiment = None  # check() reports it
    embodiment = embodiment or default_embodiment(cfg)
    return f"train/{cfg.task}/{embodiment}/{cfg.policy.name}", f"{{stamp}}-seed{cfg.seed}"


def run(_cfg: DictConfig, prepared: Prepared, out: pathlib.Path) -> int:
    cfg, model_mod, settings = prepared.cfg, prepared.model, prepared.settings
    device, demos, meta = prepared.device, prepared.demos, prepared.demos.meta
    torch.manual_seed(settings.seed)
    shapes = {g: tuple(v.shape[1:]) for g, v in demos.obs.items()}
    layout = list(meta["action_layout"]["actuators"])
    policy_cfg = OmegaConf.to_container(cfg.policy)
    model = model_mod.make_model(policy_cfg, shapes, len(layout))
    normalizer = fit_normalizer(demos)
    run_dir = open_run_dir(out, cfg)
    config = OmegaConf.to_container(cfg)
    fixed = {"kind": cfg.policy.name, "task": meta["task"], "embodiment": meta["embodiment"],
             "obs": model_mod.OBS, "groups": list(demos.obs),
             "shapes": {g: list(s) for g, s in shapes.items()}, "action_layout": layout,
             "config": config, "dataset": demos.source}

    def save(name: str, state: dict) -> None:
        cpu = {k: {n: t.cpu() for n, t in v.items()} if k in ("model", "ema") else v
               for k, v in state.items()}
        save_checkpoint(run_dir / f"{name}.pt", {**fixed, **cpu})

    log = RunLog(run_dir, config, OmegaConf.to_container(cfg.wandb))
    params = sum(p.numel() for p in model.parameters())
    print(f"training {cfg.policy.name} ({params / 1e6:.1f} M parameters) on "
          f"{demos.num_episodes} episodes, {len(demos.actions)} frames, {device} -> {run_dir}",
          file=sys.stderr)
    try:
        summary = train_policy(model, demos, normalizer, settings, device, log, save)
    except KeyboardInterrupt:
        print(f"\ninterrupted: checkpoints so far are in {run_dir}", file=sys.stderr)
        return 130
    finally:
        log.close()
    summary = {"policy": cfg.policy.name, "task": meta["task"],
               "embodiment": meta["embodiment"], "dataset": demos.source,
               "device": str(device), "parameters": params, **summary,
               "checkpoint": str(run_dir / "best.pt"), "run_dir": str(run_dir)}
    write_json(run_dir / "summary.json", summary)
    print(json.dumps(summary))
    return 0


COMMAND = register(Command("train", run, check, run_dir, validate))
main = COMMAND.main
hydra_entry = hydra_main(COMMAND)
