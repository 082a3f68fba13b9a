"""Regenerate observations from recorded simulator states, or re-simulate the actions.

State replay never steps physics: each episode's reset key is replayed (`reset_to`:
goal, variation, reset poses), then each recorded `sim_state` is put back (`restore`)
and the requested observation groups are computed. Frames are independent once the key
is set, so the env's worlds hold consecutive frames of one episode. Observations are
written per frame (no history axis): stacking is a training-time choice, and the
preset's history length is kept in `meta/dexbench.json`. Action replay re-simulates each
episode's actions from its first recorded state and reports how far the states drift.
Both first check the dataset's files against the checksums recorded when they were
written, so damage that still parses never propagates into new data.
"""

from __future__ import annotations

import pathlib
import shutil

import numpy as np
import torch
from tqdm import tqdm

from dexbench.data.features import ACTION, SIM_STATE, dataset_features, feature_key, frame_value
from dexbench.data.files import digests, publish, write_json
from dexbench.data.lerobot_io import create_dataset, read_episodes
from dexbench.data.meta import (
    META_FILE,
    DatasetError,
    code_changes,
    env_from_config,
    read_meta,
    verify_files,
)
from dexbench.envs.dex_env import STATE_SPEC, DexEnv
from dexbench.envs.observations import resolve_preset
from dexbench.sim.backend import state_layout


def default_out(source: pathlib.Path, obs: str | list[str]) -> pathlib.Path:
    """`<source>-<preset>` beside the source dataset."""
    label = obs if isinstance(obs, str) else "_".join(g.replace("/", "_") for g in obs)
    return source.with_name(f"{source.name}-{label}")


def replay_states(source: pathlib.Path, out: pathlib.Path, obs: str | list[str],
                  num_envs: int = 8, force: bool = False, progress: bool = True,
                  **env_kwargs) -> list[str]:
    """Write the observations `obs` of every recorded frame as a new dataset at `out`.

    `env_kwargs` go to the env (cameras, image_size, renderer, num_points, nthread).
    Returns what changed in the code since recording (replaying anyway needs `force`).
    """
    meta = read_meta(source)
    verify_files(source, meta)
    episodes = read_episodes(source, meta, observations=False)
    if out.exists():
        raise DatasetError(f"{out} exists; remove it or pass out=<another folder>")
    env = env_from_config(meta["env_config"], num_envs=num_envs, obs=obs, history=0,
                          **env_kwargs)
    changes = code_changes(meta, env)
    if changes and not force:
        raise DatasetError(f"{source} was recorded with other code ({'; '.join(changes)}); "
                           "its observations would not be reproduced. Re-collect, or pass "
                           "force=true to replay anyway")
    build = out.with_name(f".{out.name}.tmp")
    shutil.rmtree(build, ignore_errors=True)
    env.reset_to([0], [episodes[0].key])
    first = env.restore([0], episodes[0].states[:1])
    features = dataset_features({g: tuple(v.shape[1:]) for g, v in first.items()},
                                meta["action_layout"]["actuators"], meta["sim_state"]["size"],
                                meta["proprio_joints"])
    try:
        dataset = create_dataset(build, features, meta["fps"], meta["embodiment"])
        with tqdm(total=sum(ep.length for ep in episodes), desc=f"replay {obs}",
                  unit="frame", disable=not progress) as bar:
            for ep in episodes:
                _write_episode(env, dataset, ep, meta["instruction"], bar)
        dataset.finalize()
    except BaseException:  # an interrupted replay leaves nothing behind
        shutil.rmtree(build, ignore_errors=True)
        raise
    camera = env.cameras
    write_json(build / META_FILE, {**meta, "repo_id": dataset.repo_id,
                                   "files": digests(build, META_FILE), "replay": {
        "source": str(source), "obs": obs, "groups": sorted(first),
        "history": resolve_preset(obs).history,
        "cameras": list(camera.cameras) if camera else [],
        "image_size": [camera.renderer.width, camera.renderer.height] if camera else None,
        "shadows": camera.renderer.shadows if camera else None,
        "code_changes": changes}})
    publish(build, out, build.with_name(f".{out.name}.old"))
    return changes


def _write_episode(env: DexEnv, dataset, ep, instruction: str, bar) -> None:
    n = env.num_envs
    env.reset_to(np.arange(n), [ep.key] * n)
    home = env.home_action.float().cpu().numpy()
    before = np.concatenate([home[None], ep.actions[:-1]])  # the action before each frame
    for t0 in range(0, ep.length, n):
        k = min(n, ep.length - t0)
        obs = env.restore(np.arange(k), ep.states[t0:t0 + k], before[t0:t0 + k])
        for j in range(k):
            dataset.add_frame({"task": instruction, ACTION: ep.actions[t0 + j],
                               SIM_STATE: ep.states[t0 + j],
                               **{feature_key(g): frame_value(g, v[j].cpu().numpy())
                                  for g, v in obs.items()}})
        bar.update(k)
    dataset.save_episode()


def replay_actions(source: pathlib.Path, num_envs: int = 8, progress: bool = True,
                   **env_kwargs) -> dict:
    """Re-simulate every episode's actions from its first state; report the drift.

    Per episode: the largest |qpos - recorded qpos| over its recorded frames, the step
    at which success first held (-1: never) and whether it holds after the last action.
    """
    meta = read_meta(source)
    verify_files(source, meta)
    episodes = read_episodes(source, meta, observations=False)
    env = env_from_config(meta["env_config"], num_envs=min(num_envs, len(episodes)),
                          obs="state", **env_kwargs)
    qpos = state_layout(env.scene.model, STATE_SPEC)["qpos"]
    rows = []
    for b in tqdm(range(0, len(episodes), env.num_envs), desc="replay actions",
                  unit="batch", disable=not progress):
        batch = episodes[b:b + env.num_envs]
        rows += _resimulate(env, batch, qpos, first_index=b)
    return {"dataset": str(source), "episodes": rows,
            "max_abs_qpos_error": max(r["max_abs_qpos_error"] for r in rows),
            "successes": sum(r["success_step"] >= 0 for r in rows),
            "code_changes": code_changes(meta, env)}


def _resimulate(env: DexEnv, batch: list, qpos: slice, first_index: int) -> list[dict]:
    k, n = len(batch), env.num_envs
    steps = max(ep.length for ep in batch)
    actions = env.home_action.float().repeat(n, steps, 1)
    recorded = np.zeros((k, steps, qpos.stop - qpos.start))
    valid = np.zeros((k, steps), dtype=bool)
    for j, ep in enumerate(batch):
        actions[j, :ep.length] = torch.from_numpy(ep.actions)
        recorded[j, :ep.length] = ep.states[:, qpos]
        valid[j, :ep.length] = True
    ids = np.arange(k)
    env.reset_to(ids, [ep.key for ep in batch])
    env.restore(ids, np.stack([ep.states[0] for ep in batch]))
    error = np.zeros(k)
    success_step = np.full(k, -1)
    final = np.zeros(k, dtype=bool)
    for t in range(steps):
        _, _, success, _, _ = env.step(actions[:, t])
        ok = success.cpu().numpy()[:k] & valid[:, t]
        success_step[ok & (success_step < 0)] = t + 1
        last = np.array([ep.length - 1 == t for ep in batch])
        final[last] = ok[last]
        if t + 1 < steps:
            drift = np.abs(env.sim_state().cpu().numpy()[:k, qpos] - recorded[:, t + 1])
            error = np.maximum(error, np.where(valid[:, t + 1], drift.max(axis=1), 0.0))
    return [{"episode_index": first_index + j, "key": list(ep.key), "length": ep.length,
             "max_abs_qpos_error": float(error[j]), "success_step": int(success_step[j]),
             "recorded_success_step": ep.success_step, "final_success": bool(final[j])}
            for j, ep in enumerate(batch)]
