"""`python bench.py explore task=PickCube`: what a freshly initialised PPO policy finds.

PPO improves only on what its own sampled actions reach. This runs the training env
(`rl.py`'s env, actions, episodes and reward terms) with the initial policy's actions,
zero mean and `rl.network.init_noise_std` noise, and counts how often they reach what the
reward pays for: the lifted object held by `lift_when_grasping`'s fingertips, and success.
A share near zero says that learning hinges on a rare event; `rl.demo_starts` (episodes
from demonstration frames) is the remedy this measures beside it.
"""

from __future__ import annotations

import inspect
import json
import pathlib

import torch
from omegaconf import DictConfig

from dexbench.cli.app import Command, register
from dexbench.cli.config import ConfigError, default_embodiment, open_run_dir, write_atomic
from dexbench.cli.rl import build_env, build_vec_env, demo_dataset
from dexbench.rl.rewards import holding, lift_when_grasping, lifted_body


def check(cfg: DictConfig, overrides: list[str]) -> None:
    if int(cfg.episodes) < 1:
        raise ConfigError(f"episodes={cfg.episodes}: run at least one episode per env")
    if "lift_when_grasping" not in cfg.rl.rewards:
        raise ConfigError("bench.py explore counts the lift_when_grasping term's events; "
                          "keep it in rl.rewards")
    demo_dataset(cfg)


def explore_in(cfg: DictConfig, out: pathlib.Path) -> dict:
    """Shares of env steps with the object held off the table, of envs that ever held it,
    the highest lift, and success of the episodes that began at the task's reset."""
    torch.manual_seed(int(cfg.seed))
    env = build_env(cfg)
    vec = build_vec_env(cfg, env)
    lift = {k: v.default for k, v in inspect.signature(lift_when_grasping).parameters.items()
            if k != "t"} | dict(cfg.rl.rewards.lift_when_grasping)
    name = lifted_body(env, lift["body"])
    if name is None:
        raise ConfigError(f"{env.task.name} lifts nothing: no lift to count")
    gen = torch.Generator(device=vec.device).manual_seed(int(cfg.seed))
    std = float(cfg.rl.network.init_noise_std)
    steps = int(cfg.episodes) * vec.max_episode_length
    n = env.num_envs
    held_lifted = torch.zeros(n, device=vec.device)
    ever_held = torch.zeros(n, dtype=torch.bool, device=vec.device)
    highest = torch.zeros(n, device=vec.device)
    for _ in range(steps):
        action = std * torch.randn(n, vec.num_actions, generator=gen, device=vec.device)
        vec.step(action)
        height = env.task.lift(env.view, name).float()
        held = holding(env, vec.groups, float(lift["force"]), int(lift["tips"]))
        held_lifted += (held & (height > float(lift["min_lift"]))).float()
        ever_held |= held
        highest = torch.maximum(highest, height)
    if steps % int(cfg.rl.num_steps_per_env):
        vec.curve.close_iteration(n * steps)  # the episodes of the last, partial iteration
    finished = [p for p in vec.curve.points if p["episodes"]]
    episodes = sum(p["episodes"] for p in finished)
    successes = sum(p["episodes"] * p["success_rate"] for p in finished)
    run_dir = open_run_dir(out, cfg)
    result = {"benchmark": "explore", "task": env.task.name, "embodiment": env.embodiment.name,
              "backend": str(cfg.sim.backend), "num_envs": n, "env_steps": n * steps,
              "action_std": std, "demo_starts": (None if vec.starts is None
                                                 else vec.starts.fraction),
              "held_lifted_step_share": held_lifted.sum().item() / (n * steps),
              "ever_held_env_share": ever_held.float().mean().item(),
              "max_lift_mean_m": round(highest.mean().item(), 4),
              "max_lift_max_m": round(highest.max().item(), 4),
              "reset_episodes": episodes,
              "reset_success_rate": successes / episodes if episodes else None,
              "run_dir": str(run_dir)}
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    return result


def _print(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    print(json.dumps(explore_in(cfg, out)))
    return 0


def _dir(cfg: DictConfig) -> tuple[str, str]:
    return "bench", f"{{stamp}}-explore-{cfg.task}-{default_embodiment(cfg)}"


BENCH_EXPLORE = register(Command("bench_explore", _print, check, _dir))
