"""`python -m dexbench snapshot task=<T> embodiment=<E> visual=<preset>`: a contact sheet.

One row per environment: every camera's RGB, the front depth (near = bright) and the
fused point cloud seen from above (colour = height). Written as a PNG under
`runs/snapshot/`, for humans to check a scene, its cameras and its variation.
"""

from __future__ import annotations

import numpy as np
import torch
from PIL import Image

from dexbench.cli.config import env_kwargs, load_config, new_run_dir
from dexbench.envs.arena import TABLE_HALF_SIZE
from dexbench.envs.camera_obs import CROP_HI, CROP_LO, THIRD_PERSON
from dexbench.tasks.registry import make_env


def _depth_image(depth: np.ndarray) -> np.ndarray:
    valid = depth < depth.max()
    lo, hi = (depth[valid].min(), depth[valid].max()) if valid.any() else (0.0, 1.0)
    level = np.where(valid, 1.0 - (depth - lo) / max(hi - lo, 1e-6), 0.0)
    return (np.stack([level, level**0.5, 1.0 - level], axis=-1) * 255).astype(np.uint8)


def _cloud_image(points: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    w, h = size
    img = np.full((h, w, 3), 30, np.uint8)
    col = ((points[:, 0] + TABLE_HALF_SIZE[0]) / (2 * TABLE_HALF_SIZE[0]) * (w - 1)).astype(int)
    row = ((TABLE_HALF_SIZE[1] - points[:, 1]) / (2 * TABLE_HALF_SIZE[1]) * (h - 1)).astype(int)
    height = (points[:, 2] - CROP_LO[2]) / (CROP_HI[2] - CROP_LO[2])
    colour = np.stack([height, 1 - np.abs(height - 0.5), 1 - height], -1) * 255
    inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
    img[row[inside], col[inside]] = colour[inside].astype(np.uint8)
    return img


def snapshot(overrides: list[str]) -> str:
    cfg = load_config("config", ["num_envs=4", "camera.width=160", "camera.height=120",
                                 *overrides])
    kwargs = env_kwargs(cfg)
    embodiment_env = make_env(**{**kwargs, "num_envs": 1})
    wrists = [f"{side}/hand/wrist_cam" for side in embodiment_env.embodiment.sides]
    kwargs.update(obs=["rgb", "depth", "pointcloud"], cameras=[*THIRD_PERSON, *wrists])
    env = make_env(**kwargs)
    obs = {k: v.numpy() if isinstance(v, torch.Tensor) else v for k, v in env.reset().items()}
    size = (int(cfg.camera.width), int(cfg.camera.height))
    rows = []
    for e in range(env.num_envs):
        tiles = [obs[f"rgb/{c}"][e] for c in (*THIRD_PERSON, *wrists)]
        tiles.append(_depth_image(obs["depth/front"][e]))
        tiles.append(_cloud_image(obs["pointcloud"][e], size))
        rows.append(np.concatenate(tiles, axis=1))
    sheet = np.concatenate(rows, axis=0)
    run_dir = new_run_dir("snapshot", f"{env.task.name}-{env.embodiment.name}", cfg)
    path = run_dir / "snapshot.png"
    tmp = run_dir / ".snapshot.png.tmp"
    Image.fromarray(sheet).save(tmp, format="PNG")
    tmp.replace(path)
    return str(path)
