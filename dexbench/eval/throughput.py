"""Evaluation throughput: the same policy on one batch of N envs (batched inference)
against one env at a time, in episodes per minute of wall time.

A policy kind with a model module (`dp`, `dp3`) can be timed without training: an
untrained checkpoint of the configured architecture costs the same per step as a trained
one, and the fixed `horizon` makes every episode equally long in both runs.
"""

from __future__ import annotations

import importlib
import pathlib
import time
from collections.abc import Callable
from types import ModuleType
from typing import Any

import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.eval.records import EpisodeRecord
from dexbench.eval.runner import run_episodes
from dexbench.eval.seeds import eval_keys
from dexbench.policies.common.checkpoint import save_checkpoint
from dexbench.policies.common.normalizer import MinMaxNormalizer
from dexbench.policies.common.protocol import Policy


def model_module(kind: str) -> ModuleType:
    """`dexbench.policies.<kind>.model`: `OBS`, `input_groups` and `make_model`."""
    try:
        return importlib.import_module(f"dexbench.policies.{kind}.model")
    except ModuleNotFoundError:
        raise ValueError(f"policy {kind!r} has no model to initialise; pass checkpoint=<path>"
                         ) from None


def untrained_checkpoint(kind: str, policy_cfg: dict[str, Any], env: DexEnv,
                         path: pathlib.Path) -> pathlib.Path:
    """A freshly initialised `kind` checkpoint for `env` (normalizer from its reset
    observations and action range), for timing only."""
    model_mod = model_module(kind)
    obs = env.reset()
    frames = {g: (v[:, -1] if env.history else v).float() for g, v in obs.items()}
    groups = model_mod.input_groups(frames)
    shapes = {g: tuple(frames[g].shape[1:]) for g in groups}
    layout = list(env.embodiment.actuators)
    model = model_mod.make_model(policy_cfg, shapes, len(layout))
    low = {g: frames[g].flatten(0, -2).min(0).values for g in groups}
    high = {g: frames[g].flatten(0, -2).max(0).values for g in groups}
    low["action"], high["action"] = env.action_low.float(), env.action_high.float()
    state = {k: v.detach().clone() for k, v in model.state_dict().items()}
    save_checkpoint(path, {
        "kind": kind, "task": env.task.name, "embodiment": env.embodiment.name,
        "obs": model_mod.OBS, "groups": groups, "shapes": {g: list(s) for g, s in shapes.items()},
        "action_layout": layout, "config": {"policy": policy_cfg}, "epoch": 0, "step": 0,
        "val_loss": None, "dataset": None, "model": state, "ema": state,
        "normalizer": MinMaxNormalizer(low, high).state_dict()})
    return path


# Untimed control steps before the clock starts: two re-plans of a chunked policy, so
# first-use costs (kernel loading, cuDNN algorithm choice, CUDA graph capture) stay out
# of the rate. A process that has just compiled the scene's kernels measured 5.2 k
# episodes/min with one warm-up step against 31.9 k in a fresh process (H100, 1,000 worlds).
WARMUP_STEPS = 17


def episodes_per_minute(env: DexEnv, policy: Policy, episodes: int, seed: int,
                        on_episode: Callable[[EpisodeRecord], None] | None = None) -> float:
    """Run `episodes` evaluation episodes on `env` after `WARMUP_STEPS` untimed steps."""
    every = torch.arange(env.num_envs)
    obs = env.reset_to(every, eval_keys(seed, range(env.num_envs)))
    policy.reset(every)
    for _ in range(WARMUP_STEPS):
        obs, *_ = env.step(policy.act(obs))
    policy.reset(every)
    started = time.perf_counter()
    run_episodes(env, policy, list(range(episodes)), seed, on_episode or (lambda _: None))
    return episodes * 60.0 / (time.perf_counter() - started)
