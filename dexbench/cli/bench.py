"""`python bench.py sim key=value ...`: environment throughput vs raw physics.

`env_steps_per_s` counts control steps of `DexEnv.step` (actions validated, physics,
success, reward, observations). `raw_physics_steps_per_s` steps the very same compiled
model with `mujoco.batch` alone, from the same states and with the same controls.
`ratio` = env physics throughput (env steps/s x decimation) / raw physics steps/s.

`python bench.py render ...`: RGB-D images/s of the CPU renderer and, with a GPU, of
mujoco_warp's ray tracer (`renderers=` picks).

`python bench.py eval ...`: evaluation episodes/min (`dexbench/cli/eval.py`).
`python bench.py train ...`: training steps/s (`dexbench/cli/bench_train.py`).
`python bench.py explore ...`: what a fresh PPO policy reaches (`dexbench/cli/bench_explore.py`).
Each verb is a Hydra main over `conf/bench_<verb>.yaml`; results go to
`runs/bench/<timestamp>-<verb>-...`.
"""

from __future__ import annotations

import json
import os
import pathlib
import platform
import sys
import time

import mujoco
import mujoco.batch
import torch
from omegaconf import DictConfig
from tqdm import tqdm

from dexbench.cli.app import Command, dispatch, register, stamp
from dexbench.cli.bench_explore import BENCH_EXPLORE
from dexbench.cli.bench_train import BENCH_TRAIN
from dexbench.cli.bench_warp import bench_sim_warp
from dexbench.cli.config import (
    default_embodiment,
    env_kwargs,
    load_config,
    open_run_dir,
    write_atomic,
)
from dexbench.cli.eval import BENCH_EVAL
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.scene import check_pair
from dexbench.sim.warp_render import WarpRenderer, default_warp_device
from dexbench.tasks.registry import make_env, task_class

USAGE = """usage: python bench.py sim [num_envs=64] [task=PickCube] [embodiment=...] ...
       python bench.py render [num_envs=16] [width=128] [height=128] [renderers=[cpu,warp]] ...
       python bench.py eval [policy=dp] [checkpoint=...] [num_envs=50] [horizon=32]
                            [backends=[cpu,warp]] [warp_episodes=1000] ...
       python bench.py train [policy=dp3] [jobs=1] [steps=300] [device=auto] ...
       python bench.py explore [task=PickCube] [num_envs=32] [rl.demo_starts.dataset=auto] ...
       python bench.py <verb> --help"""


def _actions(env: DexEnv, count: int, noise: float, seed: int) -> list[torch.Tensor]:
    gen = torch.Generator().manual_seed(seed)
    span = env.action_high - env.action_low
    out = []
    for _ in range(count):
        eps = torch.randn(env.num_envs, env.action_dim, generator=gen, dtype=torch.float64)
        out.append(torch.clamp(env.home_action + noise * span * eps, env.action_low,
                               env.action_high))
    return out


def check(cfg: DictConfig, overrides: list[str]) -> None:
    """The env settings and the task x embodiment pair."""
    env_kwargs(cfg)
    check_pair(task_class(cfg.task), default_embodiment(cfg))


def _dir(verb: str) -> object:
    def run_dir(cfg: DictConfig) -> tuple[str, str]:
        return "bench", f"{{stamp}}-{verb}-{cfg.task}-{default_embodiment(cfg)}"

    return run_dir


def bench_sim(overrides: list[str]) -> dict:
    """Programmatic `python bench.py sim ...`."""
    cfg = load_config("bench_sim", overrides)
    check(cfg, overrides)
    return bench_sim_in(cfg, SIM.folder(cfg, stamp()))


def bench_sim_in(cfg: DictConfig, out: pathlib.Path) -> dict:
    if cfg.sim.backend == "warp":
        return bench_sim_warp(cfg, out)
    env = make_env(**env_kwargs(cfg))
    run_dir = open_run_dir(out, cfg)
    n, steps, warmup = env.num_envs, int(cfg.steps), int(cfg.warmup)
    actions = _actions(env, 16, float(cfg.action_noise), int(cfg.seed))
    env.reset()
    start_state = env.sim.get_state()
    for i in tqdm(range(warmup), desc="warm-up", leave=False):
        env.step(actions[i % len(actions)])
    env.reset()
    t0 = time.perf_counter()
    for i in tqdm(range(steps), desc=f"env x{n}", leave=False):
        env.step(actions[i % len(actions)])
    env_time = time.perf_counter() - t0

    raw = mujoco.batch.Batch(env.scene.model, n, nthread=env.sim.nthread)
    raw.state[:] = start_state.numpy()
    ctrl = raw.bind("ctrl")
    raw_actions = [a.numpy() for a in actions]
    for i in range(warmup):
        ctrl[:] = raw_actions[i % len(raw_actions)]
        raw.step(nstep=env.decimation)
    raw.state[:] = start_state.numpy()
    t0 = time.perf_counter()
    for i in tqdm(range(steps), desc=f"raw x{n}", leave=False):
        ctrl[:] = raw_actions[i % len(raw_actions)]
        raw.step(nstep=env.decimation)
    raw_time = time.perf_counter() - t0

    env_sps = n * steps / env_time
    raw_sps = n * steps * env.decimation / raw_time
    result = {
        "benchmark": "sim",
        "task": env.task.name,
        "embodiment": env.embodiment.name,
        "backend": cfg.sim.backend,
        "num_envs": n,
        "nthread": env.sim.nthread,
        "steps": steps,
        "decimation": env.decimation,
        "env_steps_per_s": round(env_sps, 1),
        "env_physics_steps_per_s": round(env_sps * env.decimation, 1),
        "raw_physics_steps_per_s": round(raw_sps, 1),
        "ratio": round(env_sps * env.decimation / raw_sps, 4),
        "mujoco": mujoco.__version__,
        "torch": torch.__version__,
        "cpu": platform.processor() or platform.machine(),
        "run_dir": str(run_dir),
    }
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    return result


def _renderers(cfg) -> list[str]:
    """`renderers=auto`: the CPU renderer, plus the warp one when there is a GPU."""
    if cfg.renderers != "auto":
        return [str(r) for r in cfg.renderers]
    return ["cpu", "warp"] if default_warp_device().startswith("cuda") else ["cpu"]


def _time_renderer(env: DexEnv, steps: int) -> float:
    """Seconds for `steps` renders of the front camera (after one untimed render)."""
    renderer = env.cameras.renderer
    renderer.render(["front"], rgb=True, depth=True)
    t0 = time.perf_counter()
    for _ in tqdm(range(steps), desc=f"render x{env.num_envs}", leave=False):
        renderer.render(["front"], rgb=True, depth=True)
    return time.perf_counter() - t0


def _renderer_label(renderer) -> str:
    if isinstance(renderer, WarpRenderer):
        return f"warp ({renderer.device})"
    return f"cpu (mujoco.Renderer, MUJOCO_GL={os.environ.get('MUJOCO_GL', '')})"


def bench_render(overrides: list[str]) -> dict:
    """Programmatic `python bench.py render ...`."""
    cfg = load_config("bench_render", overrides)
    check(cfg, overrides)
    return bench_render_in(cfg, RENDER.folder(cfg, stamp()))


def bench_render_in(cfg: DictConfig, out: pathlib.Path) -> dict:
    """RGB-D images per second of one camera (an RGB + depth pair counts once), per
    renderer, with the images delivered where the env's tensors live (CPU for the CPU
    backend) and, for warp on a GPU, also kept on the GPU; the returned object is the
    first renderer's first result, with every result listed."""
    width, height = int(cfg.width), int(cfg.height)
    results = []
    for kind in _renderers(cfg):
        kwargs = env_kwargs(cfg)
        kwargs.update(obs=["rgb", "depth"], image_size=(width, height), renderer=kind)
        env = make_env(**kwargs)
        env.reset()
        renderer = env.cameras.renderer
        runs = [("on the env's device", env.device)]
        if isinstance(renderer, WarpRenderer) and renderer.device != "cpu":
            runs.append(("kept on the GPU", torch.device(renderer.device)))
        for where, device in runs:
            if isinstance(renderer, WarpRenderer):
                renderer.output_device = device
            elapsed = _time_renderer(env, int(cfg.steps))
            results.append({
                "renderer": _renderer_label(renderer),
                "images": f"{where} ({device})",
                "num_envs": env.num_envs,
                "resolution": [width, height],
                "images_per_s": round(env.num_envs * int(cfg.steps) / elapsed, 1),
            })
            print(f"{results[-1]['images_per_s']:,.0f} RGB-D images/s "
                  f"({results[-1]['renderer']}, images {results[-1]['images']}, "
                  f"{env.num_envs} envs, {width}x{height})")
    run_dir = open_run_dir(out, cfg)
    result = {"benchmark": "render", **results[0], "task": env.task.name,
              "embodiment": env.embodiment.name, "results": results,
              "mujoco": mujoco.__version__, "gpu": _gpu_name(), "run_dir": str(run_dir)}
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    return result


def _gpu_name() -> str | None:
    return torch.cuda.get_device_name(0) if torch.cuda.is_available() else None


def format_table(result: dict) -> str:
    where = result.get("device") or f"{result['nthread']} threads"
    rows = [("task", result["task"]), ("embodiment", result["embodiment"]),
            ("backend", f"{result['backend']} ({where})"),
            ("num_envs", result["num_envs"]), ("decimation", result["decimation"]),
            ("env steps/s (60 Hz control)", f"{result['env_steps_per_s']:,.0f}"),
            ("env physics steps/s", f"{result['env_physics_steps_per_s']:,.0f}"),
            ("raw physics steps/s", f"{result['raw_physics_steps_per_s']:,.0f}"),
            ("ratio env/raw", f"{result['ratio']:.3f}")]
    if "ratio_without_contact" in result:
        rows += [("env steps/s, no contact group",
                  f"{result['env_steps_per_s_without_contact']:,.0f}"),
                 ("ratio env/raw, no contact group", f"{result['ratio_without_contact']:.3f}")]
    if "camera_env_steps_per_s" in result:
        w, h = result["camera_resolution"]
        rows += [(f"+ 1 RGB-D {w}x{h} camera, envs", result["camera_num_envs"]),
                 ("  env steps/s = images/s", f"{result['camera_env_steps_per_s']:,.0f}"),
                 ("  the same without shadows",
                  f"{result['camera_no_shadows_env_steps_per_s']:,.0f}")]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _print_sim(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    result = bench_sim_in(cfg, out)
    print(format_table(result))
    print(json.dumps(result))
    return 0


def _print_render(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    print(json.dumps(bench_render_in(cfg, out)))
    return 0


SIM = register(Command("bench_sim", _print_sim, check, _dir("sim")))
RENDER = register(Command("bench_render", _print_render, check, _dir("render")))
VERBS = {"sim": SIM, "render": RENDER, "eval": BENCH_EVAL, "train": BENCH_TRAIN,
         "explore": BENCH_EXPLORE}


def main(argv: list[str]) -> int:
    """Programmatic `python bench.py <verb> ...`; 2 with the usage for an unknown verb."""
    if not argv or argv[0] not in VERBS:
        print(USAGE, file=sys.stderr)
        return 2
    return VERBS[argv[0]].main(argv[1:])


def entry() -> None:
    """`python bench.py <verb> ...`: the verb's Hydra main."""
    dispatch(VERBS, sys.argv[1:], USAGE)
