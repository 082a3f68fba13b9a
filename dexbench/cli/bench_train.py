"""`python bench.py train policy=dp3 jobs=4`: gradient steps/s of the training loop.

The loop is `train_policy` itself, on random frames shaped like the task's observations
for the policy (so no dataset is needed) and with no checkpoint writes; `jobs` processes
train at once on the same device, as a sweep's trainings share a GPU, and their summed
rate is what a sweep gets. Sizing a GPU sweep (how many epochs fit a time cap) starts here.
"""

from __future__ import annotations

import dataclasses
import json
import multiprocessing
import pathlib
import time

import numpy as np
import torch
from omegaconf import DictConfig, OmegaConf

from dexbench.cli.app import Command, register
from dexbench.cli.config import ConfigError, env_kwargs, open_run_dir, write_atomic
from dexbench.cli.train import model_module, settings_of
from dexbench.policies.common.demos import Demos
from dexbench.policies.common.runner import resolve_device
from dexbench.policies.common.training import TrainSettings, fit_normalizer, train_policy
from dexbench.tasks.registry import make_env

EPISODE = 256


def synthetic_demos(cfg: DictConfig, obs: str) -> Demos:
    """Random frames with the shapes the task's env gives the policy's preset."""
    kwargs = {**env_kwargs(cfg), "num_envs": 1, "obs": obs, "history": 0}
    env = make_env(**kwargs)
    first = env.reset()
    frames = int(cfg.frames)
    rng = np.random.default_rng(int(cfg.seed))
    data = {g: rng.random((frames, *v.shape[1:]), dtype=np.float32) for g, v in first.items()}
    actions = rng.uniform(-1, 1, (frames, env.action_dim)).astype(np.float32)
    ends = np.arange(EPISODE, frames + EPISODE, EPISODE).clip(max=frames)
    return Demos(meta={"task": env.task.name, "embodiment": env.embodiment.name},
                 actions=actions, obs=data, episode_ends=np.unique(ends), source="synthetic")


def _settings(cfg: DictConfig, steps: int) -> TrainSettings:
    """train.py's settings for the policy, run for `steps` steps with nothing held out,
    no checkpoint writes and no progress bar."""
    return dataclasses.replace(settings_of(cfg), epochs=10**6, max_steps=steps,
                               val_fraction=0.0, save_every=10**6, progress=False)


class _NoLog:
    def epoch(self, row: dict) -> None:
        pass


def _one(cfg_yaml: str) -> dict:
    """One training copy: untimed warm-up steps, then the timed ones."""
    cfg = OmegaConf.create(cfg_yaml)
    kind = model_module(cfg.policy.name)
    demos = synthetic_demos(cfg, kind.OBS)
    device = resolve_device(str(cfg.device))
    shapes = {g: tuple(v.shape[1:]) for g, v in demos.obs.items()}
    model = kind.make_model(OmegaConf.to_container(cfg.policy), shapes, demos.actions.shape[1])
    normalizer = fit_normalizer(demos)
    train_policy(model, demos, normalizer, _settings(cfg, int(cfg.warmup)), device, _NoLog(),
                 lambda name, state: None)
    if device.type == "cuda":
        torch.cuda.synchronize(device)
    t0 = time.perf_counter()
    train_policy(model, demos, normalizer, _settings(cfg, int(cfg.steps)), device, _NoLog(),
                 lambda name, state: None)
    if device.type == "cuda":
        torch.cuda.synchronize(device)
    elapsed = time.perf_counter() - t0
    return {"steps_per_s": round(int(cfg.steps) / elapsed, 2),
            "parameters_m": round(sum(p.numel() for p in model.parameters()) / 1e6, 1),
            "device": str(device)}


def check(cfg: DictConfig, overrides: list[str]) -> None:
    if int(cfg.jobs) < 1 or int(cfg.steps) < 1 or int(cfg.frames) < 2 * EPISODE:
        raise ConfigError(f"need jobs >= 1, steps >= 1 and frames >= {2 * EPISODE}")
    model_module(cfg.policy.name)
    try:
        resolve_device(str(cfg.device))
    except (ValueError, RuntimeError) as err:
        raise ConfigError(f"device={cfg.device}: {err}") from None


def bench_train_in(cfg: DictConfig, out: pathlib.Path) -> dict:
    """Every copy's steps/s and their sum; the model's size and the GPU."""
    text = OmegaConf.to_yaml(cfg, resolve=True)
    jobs = int(cfg.jobs)
    if jobs == 1:
        copies = [_one(text)]
    else:  # spawned: CUDA cannot be forked
        with multiprocessing.get_context("spawn").Pool(jobs) as pool:
            copies = pool.map(_one, [text] * jobs)
    run_dir = open_run_dir(out, cfg)
    result = {"benchmark": "train", "policy": cfg.policy.name, "task": cfg.task,
              "parameters_m": copies[0]["parameters_m"], "device": copies[0]["device"],
              "gpu": torch.cuda.get_device_name(0) if torch.cuda.is_available() else None,
              "batch_size": int(cfg.policy.optim.batch_size), "jobs": jobs,
              "steps_per_s_each": [c["steps_per_s"] for c in copies],
              "steps_per_s_total": round(sum(c["steps_per_s"] for c in copies), 2),
              "torch": torch.__version__, "run_dir": str(run_dir)}
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    return result


def _print(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    print(json.dumps(bench_train_in(cfg, out)))
    return 0


def _dir(cfg: DictConfig) -> tuple[str, str]:
    return "bench", f"{{stamp}}-train-{cfg.policy.name}-{cfg.task}"


BENCH_TRAIN = register(Command("bench_train", _print, check, _dir))
