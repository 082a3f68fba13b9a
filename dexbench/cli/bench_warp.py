"""`python bench.py sim sim.backend=warp ...`: GPU environment throughput vs raw physics.

`env_steps_per_s` counts `DexEnv.step` calls x envs (60 Hz control steps: actions
validated, one CUDA graph of physics, success, reward, state observations).
`raw_physics_steps_per_s` replays the same controls from the same start state through
the env's own compiled model and data with plain `mujoco_warp.step` (graph captured,
`decimation` steps per launch, controls written between launches), so the ratio
isolates what the environment adds (also without the `contact` group, whose forces
need one more constraint solve per step). With `camera_envs` > 0 the environment is timed
again at that size with one RGB-D camera (`width` x `height`, ray traced on the GPU,
images left on the GPU), with and without shadows (a shadow ray per lit pixel): every
env step renders one image per env, so env steps/s = images/s.
"""

from __future__ import annotations

import datetime as dt
import json
import pathlib
import time

import mujoco
import torch
from omegaconf import DictConfig
from tqdm import tqdm

from dexbench.cli.config import env_kwargs, open_run_dir, write_atomic
from dexbench.envs.dex_env import DexEnv
from dexbench.tasks.registry import make_env

STATE_GROUPS = ["policy", "proprio", "contact", "state", "goal"]


def _sync(env: DexEnv) -> None:
    if env.device.type == "cuda":
        torch.cuda.synchronize(env.device)


def _actions(env: DexEnv, count: int, noise: float, seed: int) -> list[torch.Tensor]:
    gen = torch.Generator().manual_seed(seed)
    span = (env.action_high - env.action_low).cpu()
    home, low, high = env.home_action.cpu(), env.action_low.cpu(), env.action_high.cpu()
    return [torch.clamp(home + noise * span * torch.randn(env.num_envs, env.action_dim,
                                                          generator=gen, dtype=torch.float64),
                        low, high).to(env.device) for _ in range(count)]


def _time_env(env: DexEnv, actions: list[torch.Tensor], steps: int, warmup: int,
              label: str) -> float:
    """Seconds for `steps` env steps after `warmup` untimed ones (graph capture)."""
    env.reset()
    for i in tqdm(range(warmup), desc=f"warm-up {label}", leave=False):
        env.step(actions[i % len(actions)])
    env.reset()
    _sync(env)
    t0 = time.perf_counter()
    for i in tqdm(range(steps), desc=f"{label} x{env.num_envs}", leave=False):
        env.step(actions[i % len(actions)])
    _sync(env)
    return time.perf_counter() - t0


def _time_raw(env: DexEnv, actions: list[torch.Tensor], steps: int, warmup: int) -> float:
    """Seconds for `steps` x decimation plain mujoco_warp steps of the env's own worlds."""
    sim, ctrl = env.sim, env.sim.field("ctrl")
    env.reset()
    start = sim.get_state()
    ids = torch.arange(env.num_envs)
    for i in range(warmup):
        ctrl[:] = actions[i % len(actions)]
        sim.raw_step(env.decimation)
    sim.set_state(ids, start)
    _sync(env)
    t0 = time.perf_counter()
    for i in tqdm(range(steps), desc=f"raw x{env.num_envs}", leave=False):
        ctrl[:] = actions[i % len(actions)]
        sim.raw_step(env.decimation)
    _sync(env)
    return time.perf_counter() - t0


def _versions() -> dict:
    import mujoco_warp
    import warp

    return {"mujoco": mujoco.__version__, "mujoco_warp": mujoco_warp.__version__,
            "warp": warp.__version__, "torch": torch.__version__}


def bench_sim_warp(cfg: DictConfig, out: pathlib.Path) -> dict:
    """The warp backend's env vs raw throughput (and with a camera); see the module doc.
    Writes `metrics.json` into the run folder `out`."""
    n, steps, warmup = int(cfg.num_envs), int(cfg.steps), int(cfg.warmup)
    kwargs = env_kwargs(cfg)
    kwargs.update(obs=STATE_GROUPS)
    env = make_env(**kwargs)
    run_dir = open_run_dir(out, cfg)
    actions = _actions(env, 16, float(cfg.action_noise), int(cfg.seed))
    env_time = _time_env(env, actions, steps, warmup, "env")
    raw_time = _time_raw(env, actions, steps, warmup)
    env_sps = n * steps / env_time
    raw_sps = n * steps * env.decimation / raw_time
    sim = env.sim
    result = {
        "benchmark": "sim", "task": env.task.name, "embodiment": env.embodiment.name,
        "backend": "warp", "device": _device_name(env), "num_envs": n, "nthread": 1,
        "steps": steps, "decimation": env.decimation,
        "nconmax": sim.nconmax, "njmax": sim.njmax,
        "env_steps_per_s": round(env_sps, 1),
        "env_physics_steps_per_s": round(env_sps * env.decimation, 1),
        "raw_physics_steps_per_s": round(raw_sps, 1),
        "ratio": round(env_sps * env.decimation / raw_sps, 4),
        "sim_warnings": int(sim.warning_counts().sum()),
    }
    del env, sim
    # The contact group needs the acceleration stage at the new state (one more solve per
    # control step); time the env without it too, to show what that stage costs.
    kwargs.update(obs=[g for g in STATE_GROUPS if g != "contact"])
    light = make_env(**kwargs)
    light_sps = n * steps / _time_env(light, actions, steps, warmup, "env w/o contact")
    result.update({"env_steps_per_s_without_contact": round(light_sps, 1),
                   "ratio_without_contact": round(light_sps * light.decimation / raw_sps, 4)})
    del light, actions
    camera_envs = int(cfg.camera_envs)
    if camera_envs > 0:
        result.update({"camera_num_envs": camera_envs,
                       "camera_resolution": [int(cfg.width), int(cfg.height)]})
        cam_steps = max(1, steps // 3)
        kwargs.update(num_envs=camera_envs, obs=[*STATE_GROUPS, "rgb", "depth"],
                      cameras=["front"], image_size=(int(cfg.width), int(cfg.height)),
                      renderer="warp")
        for shadows, key in ((True, "camera"), (False, "camera_no_shadows")):
            cam = make_env(**{**kwargs, "shadows": shadows})
            cam_actions = _actions(cam, 16, float(cfg.action_noise), int(cfg.seed))
            cam_sps = camera_envs * cam_steps / _time_env(cam, cam_actions, cam_steps, warmup,
                                                          key.replace("_", " "))
            result[f"{key}_env_steps_per_s"] = round(cam_sps, 1)
            del cam, cam_actions
    result.update({**_versions(), "date": dt.date.today().isoformat(),
                   "run_dir": str(run_dir)})
    write_atomic(run_dir / "metrics.json", json.dumps(result, indent=2) + "\n")
    return result


def _device_name(env: DexEnv) -> str:
    if env.device.type == "cuda":
        return torch.cuda.get_device_name(env.device)
    return "warp CPU device"
