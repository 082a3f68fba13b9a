"""`python rl.py rl.algo=sac` (or `sb3_ppo`): Stable-Baselines3 on the env PPO uses.

The batched env, reward terms, actions, episode length and success curve are
`RslVecEnv`'s, seen through `Sb3VecEnv` and SB3's `VecNormalize` (observations only); the
budget is `rl.max_iterations` x `rl.num_steps_per_env` x envs steps or `rl.max_minutes`,
whichever comes first. Writes `model.zip`, `vecnormalize.pkl`, `policy.json` (with the
algorithm: `eval.py policy=rl` loads it), `curve.jsonl`/`curve.png` and `metrics.json`.
"""

from __future__ import annotations

import json
import pathlib
import time
from typing import Any

from omegaconf import DictConfig, OmegaConf
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.vec_env import VecNormalize
from tqdm import tqdm

from dexbench.policies.common.run_log import log_curve
from dexbench.rl.curve import plot_curve
from dexbench.rl.sb3_env import ALGOS, MODEL_FILE, NORM_FILE, Sb3VecEnv
from dexbench.rl.vec_env import RslVecEnv


def record_curve(new: list[dict], curve_file: pathlib.Path, wandb_run: Any,
                 bar: tqdm) -> None:
    """New curve points (one per iteration, PPO's or SB3's) to `curve.jsonl`, W&B and the
    progress bar."""
    with open(curve_file, "a") as f:
        f.writelines(json.dumps(p) + "\n" for p in new)
    log_curve(wandb_run, new)
    bar.update(len(new))
    last = [p["success_rate"] for p in new if p["success_rate"] is not None]
    bar.set_postfix(success=f"{last[-1]:.2f}" if last else "-",
                    reward=f"{new[-1]['mean_reward']:.3f}")


class _Progress(BaseCallback):
    """Appends the curve's new points (and logs them to the W&B run, if any), moves the
    bar, and stops at the time budget."""

    def __init__(self, vec: RslVecEnv, curve_file: pathlib.Path, bar: tqdm,
                 budget_s: float, wandb_run: Any = None) -> None:
        super().__init__()
        self.vec, self.curve_file, self.bar, self.budget_s = vec, curve_file, bar, budget_s
        self.wandb_run = wandb_run
        self.start, self.written = time.perf_counter(), 0

    def _on_step(self) -> bool:
        new = self.vec.curve.points[self.written:]
        if new:
            record_curve(new, self.curve_file, self.wandb_run, self.bar)
            self.written += len(new)
        return time.perf_counter() - self.start < self.budget_s


def _model(cfg: DictConfig, venv: VecNormalize, run_dir: pathlib.Path, device: str):
    rl, sb = cfg.rl, cfg.rl.sb3
    common = {"learning_rate": float(sb.learning_rate), "gamma": float(rl.ppo.gamma),
              "batch_size": int(sb.batch_size), "seed": int(cfg.seed), "device": device,
              "policy_kwargs": {"net_arch": list(sb.net_arch)}, "verbose": 0,
              "tensorboard_log": str(run_dir)}
    if rl.algo == "sac":
        return ALGOS["sac"]("MlpPolicy", venv, buffer_size=int(sb.buffer_size),
                            learning_starts=int(sb.learning_starts), train_freq=1,
                            gradient_steps=int(sb.gradient_steps), **common)
    return ALGOS["sb3_ppo"]("MlpPolicy", venv, n_steps=int(rl.num_steps_per_env),
                            n_epochs=int(rl.ppo.num_learning_epochs),
                            gae_lambda=float(rl.ppo.lam), clip_range=float(rl.ppo.clip_param),
                            **common)


def train_sb3(cfg: DictConfig, vec: RslVecEnv, run_dir: pathlib.Path, device: str,
              wandb_run: Any = None) -> dict:
    """Train, save, plot (curve points also to `wandb_run`); the result as `rl.py` prints
    it."""
    rl, env = cfg.rl, vec.env
    venv = VecNormalize(Sb3VecEnv(vec), norm_obs=True, norm_reward=False,
                        gamma=float(rl.ppo.gamma))
    model = _model(cfg, venv, run_dir, device)
    steps = int(rl.max_iterations) * int(rl.num_steps_per_env) * env.num_envs
    label = f"{rl.algo} {env.task.name} x{env.num_envs}"
    bar = tqdm(total=int(rl.max_iterations), desc=label, unit="it")
    progress = _Progress(vec, run_dir / "curve.jsonl", bar, 60.0 * float(rl.max_minutes),
                         wandb_run)
    model.learn(steps, callback=progress, progress_bar=False)
    bar.close()
    model.save(run_dir / MODEL_FILE)
    venv.save(str(run_dir / NORM_FILE))
    plot_curve(vec.curve.points, run_dir / "curve.png",
               f"{rl.algo} {env.task.name} ({env.embodiment.name}, {env.num_envs} envs, "
               f"{cfg.sim.backend})")
    finished = [p for p in vec.curve.points if p["success_rate"] is not None]
    return {"task": env.task.name, "embodiment": env.embodiment.name, "algo": str(rl.algo),
            "num_envs": env.num_envs, "backend": str(cfg.sim.backend),
            "iterations": len(vec.curve.points), "env_steps": int(model.num_timesteps),
            "wall_s": round(time.perf_counter() - progress.start, 1),
            "final_success_rate": finished[-1]["success_rate"] if finished else None,
            "checkpoint": str(run_dir / MODEL_FILE), "run_dir": str(run_dir),
            "sb3": OmegaConf.to_container(rl.sb3)}
