"""`python rl.py task=<T> embodiment=<E> num_envs=4096`: RSL-RL PPO on a batched env.

Trains on the weighted reward terms of `conf/rl_rewards/<preset>.yaml` (the task's dense
reward plus grasp and action terms by default; `dexbench.rl.rewards`) with the state
observation groups for the actor and those plus `privileged` for the critic, on
`sim.backend` (warp on a GPU; cpu for smoke tests: `sim.backend=cpu num_envs=4
rl.max_iterations=2`). Stops after `rl.max_iterations` or
`rl.max_minutes`, whichever comes first. `rl.demo_starts.dataset=<folder>|auto` starts a
share (`rl.demo_starts.fraction`) of the training episodes from the expert's recorded
demonstrations (`dexbench.rl.demo_starts`; auto: `runs/datasets/<task>/<emb>/seed0`).
Writes `runs/rl/<timestamp>-<task>-<emb>/` (Hydra's run folder): config, RSL-RL
checkpoints (`model_<it>.pt`) and TensorBoard logs, `policy.json` (what
`python eval.py policy=rl checkpoint=<folder>` needs), `curve.jsonl` and `curve.png`
(success of finished training episodes vs wall time) and `metrics.json`; with
`wandb.enabled=true` (conf/wandb/: offline by default) each curve point goes to W&B too,
under `wandb/` in the run folder.
"""

from __future__ import annotations

import contextlib
import json
import pathlib
import time

import torch
from omegaconf import DictConfig, OmegaConf
from rsl_rl.runners import OnPolicyRunner
from tqdm import tqdm

from dexbench.cli.app import Command, hydra_main, register, stamp
from dexbench.cli.config import (
    ConfigError,
    dataset_path,
    default_embodiment,
    env_kwargs,
    load_config,
    open_run_dir,
    write_atomic,
)
from dexbench.cli.rl_sb3 import record_curve, train_sb3
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.scene import check_pair
from dexbench.policies.common.run_log import (
    finish_wandb,
    start_wandb,
    wandb_missing,
)
from dexbench.policies.rl import META_FILE
from dexbench.rl.actions import ActionMap
from dexbench.rl.config import runner_config
from dexbench.rl.curve import plot_curve
from dexbench.rl.demo_starts import DemoStarts
from dexbench.rl.rewards import check_terms
from dexbench.rl.sb3_env import ALGOS
from dexbench.rl.vec_env import ACTOR_GROUPS, CRITIC_EXTRA, RslVecEnv
from dexbench.tasks.registry import make_env, task_class


def _device(cfg: DictConfig, env: DexEnv) -> str:
    name = str(cfg.rl.device)
    return str(env.device) if name == "auto" else name


def build_env(cfg: DictConfig) -> DexEnv:
    """The training env: every state group and `privileged`, resets done by the wrapper."""
    if cfg.obs != "state":
        raise ConfigError(f"rl.py trains on state observations; got obs={cfg.obs}")
    kwargs = env_kwargs(cfg)
    kwargs.update(obs=[*ACTOR_GROUPS, *CRITIC_EXTRA], auto_reset=False)
    return make_env(**kwargs)


def action_map(cfg: DictConfig, env: DexEnv) -> ActionMap:
    """`rl.action_mode` (joints or synergy, with `rl.synergies`) at `rl.action_scale`."""
    try:
        return ActionMap(env, str(cfg.rl.action_mode), float(cfg.rl.action_scale),
                         tuple(cfg.rl.synergies))
    except ValueError as err:
        raise ConfigError(f"rl.action_mode/rl.synergies: {err}") from None


def episode_steps(cfg: DictConfig, env: DexEnv) -> int | None:
    """Control steps of a training episode (`rl.episode_seconds`; null: the task's)."""
    seconds = cfg.rl.episode_seconds
    if seconds is None:
        return None
    steps = round(float(seconds) / env.control_dt)
    if not 0 < steps <= env.episode_steps:
        raise ConfigError(f"rl.episode_seconds={seconds} must be in (0, "
                          f"{env.task.episode_seconds}] (the task's time limit)")
    return steps


def demo_dataset(cfg: DictConfig) -> pathlib.Path | None:
    """`rl.demo_starts.dataset`: None (off), a folder, or `auto`, the folder `python
    collect.py task=<T> embodiment=<E>` writes; an error that says how to make it."""
    name = cfg.rl.demo_starts.dataset
    if name is None:
        return None
    embodiment = default_embodiment(cfg)
    path = (dataset_path(cfg.task, embodiment, "seed0") if name == "auto"
            else pathlib.Path(str(name)))
    if not path.is_dir():
        raise ConfigError(f"rl.demo_starts.dataset: no demonstrations at {path}; collect them "
                          f"with `python collect.py task={cfg.task} embodiment={embodiment} "
                          "num_demos=50` (or pass rl.demo_starts.dataset=<folder>)")
    return path


def demo_starts(cfg: DictConfig, env: DexEnv) -> DemoStarts | None:
    path = demo_dataset(cfg)
    if path is None:
        return None
    try:
        return DemoStarts.from_dataset(path, env, float(cfg.rl.demo_starts.fraction),
                                       int(cfg.seed))
    except ValueError as err:
        raise ConfigError(f"rl.demo_starts: {err}") from None


def build_vec_env(cfg: DictConfig, env: DexEnv) -> RslVecEnv:
    """The training env as PPO and the SB3 algorithms (and `bench.py explore`) see it:
    `rl.*` actions, reward terms, episode length and demonstration starts."""
    rl = cfg.rl
    return RslVecEnv(env, action_map(cfg, env), OmegaConf.to_container(rl.rewards),
                     int(rl.num_steps_per_env), episode_steps(cfg, env),
                     cfg=OmegaConf.to_container(cfg, resolve=True),
                     starts=demo_starts(cfg, env))


def _meta(cfg: DictConfig, env: DexEnv, vec: RslVecEnv) -> dict:
    obs = vec.get_observations()
    return {"task": env.task.name, "embodiment": env.embodiment.name,
            "actuators": list(env.embodiment.actuators),
            "actor_groups": list(vec.actor_groups), "critic_groups": list(vec.critic_groups),
            "actor_dim": int(obs["actor"].shape[1]), "critic_dim": int(obs["critic"].shape[1]),
            **vec.action_map.describe(),
            "network": OmegaConf.to_container(cfg.rl.network, resolve=True),
            "control_dt": env.control_dt, "sim_backend": str(cfg.sim.backend),
            "algo": str(cfg.rl.algo)}


def check(cfg: DictConfig, overrides: list[str]) -> None:
    rl = cfg.rl
    if int(rl.max_iterations) < 1 or float(rl.max_minutes) <= 0:
        raise ConfigError("rl.max_iterations must be >= 1 and rl.max_minutes > 0")
    if cfg.obs != "state":
        raise ConfigError(f"rl.py trains on state observations; got obs={cfg.obs}")
    if rl.algo not in ("ppo", *ALGOS):
        raise ConfigError(f"rl.algo={rl.algo}: choose ppo (RSL-RL), {', '.join(ALGOS)} "
                          "(Stable-Baselines3)")
    try:
        check_terms(OmegaConf.to_container(rl.rewards))
    except ValueError as err:
        raise ConfigError(str(err)) from None
    missing = wandb_missing(OmegaConf.to_container(cfg.wandb))
    if missing:
        raise ConfigError(missing)
    env_kwargs(cfg)
    check_pair(task_class(cfg.task), default_embodiment(cfg))
    if not 0.0 <= float(rl.demo_starts.fraction) <= 1.0:
        raise ConfigError(f"rl.demo_starts.fraction={rl.demo_starts.fraction}: use a share "
                          "in [0, 1]")
    demo_dataset(cfg)


def run_dir(cfg: DictConfig) -> tuple[str, str]:
    return "rl", f"{{stamp}}-{cfg.task}-{default_embodiment(cfg)}"


def train(overrides: list[str]) -> dict:
    """Programmatic `python rl.py ...`: the result."""
    cfg = load_config("rl", overrides)
    check(cfg, overrides)
    return train_in(cfg, COMMAND.folder(cfg, stamp()))


def train_in(cfg: DictConfig, out: pathlib.Path) -> dict:
    rl = cfg.rl
    torch.manual_seed(int(cfg.seed))
    env = build_env(cfg)
    run_dir = open_run_dir(out, cfg)
    vec = build_vec_env(cfg, env)
    write_atomic(run_dir / META_FILE, json.dumps(_meta(cfg, env, vec), indent=2) + "\n")
    wandb_run = start_wandb(run_dir, OmegaConf.to_container(cfg, resolve=True),
                            OmegaConf.to_container(cfg.wandb), "rl")
    if rl.algo != "ppo":
        result = train_sb3(cfg, vec, run_dir, _device(cfg, env), wandb_run)
        write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
        finish_wandb(wandb_run, result)
        return result
    # RSL-RL's per-iteration console report goes to a file; the console shows a bar.
    runner_log = open(run_dir / "rsl_rl.log", "w")  # noqa: SIM115  (closed below)
    with contextlib.redirect_stdout(runner_log):
        runner = OnPolicyRunner(vec, runner_config(rl), log_dir=str(run_dir),
                                device=_device(cfg, env))
    start = time.perf_counter()
    budget_s = 60.0 * float(rl.max_minutes)
    total, done = int(rl.max_iterations), 0
    bar = tqdm(total=total, desc=f"PPO {env.task.name} x{env.num_envs}", unit="it")
    curve_file = run_dir / "curve.jsonl"
    while done < total and time.perf_counter() - start < budget_s:
        chunk = min(int(rl.chunk), total - done)
        with contextlib.redirect_stdout(runner_log):
            runner.learn(chunk, init_at_random_ep_len=bool(rl.init_at_random_ep_len)
                         and done == 0)
        # learn() stops at its last iteration's number; the next chunk continues after it
        runner.current_learning_iteration += 1
        if new := vec.curve.points[done:]:
            record_curve(new, curve_file, wandb_run, bar)
        done += chunk
    bar.close()
    runner_log.close()
    plot_curve(vec.curve.points, run_dir / "curve.png",
               f"PPO {env.task.name} ({env.embodiment.name}, {env.num_envs} envs, "
               f"{cfg.sim.backend})")
    finished = [p for p in vec.curve.points if p["success_rate"] is not None]
    result = {"task": env.task.name, "embodiment": env.embodiment.name,
              "num_envs": env.num_envs, "backend": str(cfg.sim.backend),
              "iterations": done, "env_steps": done * int(rl.num_steps_per_env) * env.num_envs,
              "wall_s": round(time.perf_counter() - start, 1),
              "final_success_rate": finished[-1]["success_rate"] if finished else None,
              "checkpoint": str(_latest_model(run_dir)), "run_dir": str(run_dir)}
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    finish_wandb(wandb_run, result)
    return result


def _latest_model(run_dir: pathlib.Path) -> pathlib.Path:
    return max(run_dir.glob("model_*.pt"), key=lambda p: p.stat().st_mtime)


def run(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    result = train_in(cfg, out)
    print(f"trained {result['iterations']} iterations in {result['wall_s']} s; "
          f"evaluate: python eval.py task={result['task']} embodiment={result['embodiment']} "
          f"policy=rl checkpoint={result['run_dir']}")
    print(json.dumps(result))
    return 0


COMMAND = register(Command("rl", run, check, run_dir))
main = COMMAND.main
hydra_entry = hydra_main(COMMAND)
