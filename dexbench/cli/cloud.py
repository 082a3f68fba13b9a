"""`python -m dexbench cloud task=<T> embodiment=<E> seed=<s> out=<file>.ply [view=true]` or
`python -m dexbench cloud dataset=<folder> episode=<e> frame=<f> out=<file>.ply [view=true]`:
one point cloud through Open3D (the optional extra: `pip install -e '.[open3d]'`).

The first form takes the `pointcloud` observation of the task's env right after reset (the
`camera.*` settings pick its cameras, image size and `num_points`); the second a frame of a
dataset that holds point clouds (one replayed with `python replay.py dataset=<folder>
obs=pointcloud`, or a Demos `.npz`). Points are world-frame metres, coloured by height as in
the snapshot sheet. `view=true` opens Open3D's viewer, on a desktop only. Writes `out` alone.
"""

from __future__ import annotations

import os
import pathlib
import sys
from types import ModuleType

import numpy as np
import torch
from omegaconf import DictConfig

from dexbench.cli.app import Command, register
from dexbench.cli.config import ConfigError, default_embodiment, env_kwargs
from dexbench.data.meta import DatasetError
from dexbench.envs.camera_obs import CROP_HI, CROP_LO
from dexbench.envs.scene import check_pair
from dexbench.policies.common.demos import Demos, available_groups, load_demos
from dexbench.tasks.registry import make_env, task_class

INSTALL = "pip install -e '.[open3d]'"


def open3d_module() -> ModuleType:
    """Open3D, or a one-line error saying how to install it (the wheel also needs the
    system's libusb-1.0, which the error names when it is missing)."""
    try:
        import open3d
    except ImportError as err:
        raise ConfigError(f"the cloud command needs Open3D: {INSTALL} "
                          f"({' '.join(str(err).split())})") from None
    return open3d


def has_display() -> bool:
    """Whether a window can open: a Linux machine needs an X or Wayland display."""
    return not sys.platform.startswith("linux") or bool(
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def env_cloud(cfg: DictConfig) -> np.ndarray:
    """(num_points, 3): the `pointcloud` observation of the task's env after reset."""
    kwargs = env_kwargs(cfg)
    kwargs.update(obs=["pointcloud"], num_envs=1)
    cloud = make_env(**kwargs).reset()["pointcloud"][0]
    return (cloud.cpu().numpy() if isinstance(cloud, torch.Tensor) else cloud).reshape(-1, 3)


def dataset_cloud(root: pathlib.Path, episode: int, frame: int) -> np.ndarray:
    """(num_points, 3): frame `frame` of episode `episode` of a dataset with point clouds."""
    if root.suffix == ".npz":
        demos = Demos.load(root)
    elif (root / "meta" / "info.json").exists() and "pointcloud" not in available_groups(root):
        raise DatasetError(f"{root} holds no point clouds (it has {available_groups(root)}); "
                           f"`python replay.py dataset={root} obs=pointcloud` writes a copy "
                           "with them")
    else:
        demos = load_demos(root, ["pointcloud"])
    if "pointcloud" not in demos.obs:
        raise DatasetError(f"{root} holds no point clouds (it has {sorted(demos.obs)})")
    ends = demos.episode_ends
    if not 0 <= episode < len(ends):
        raise ConfigError(f"episode={episode}: {root} has episodes 0..{len(ends) - 1}")
    start = int(ends[episode - 1]) if episode else 0
    length = int(ends[episode]) - start
    if not 0 <= frame < length:
        raise ConfigError(f"frame={frame}: episode {episode} has frames 0..{length - 1}")
    return demos.obs["pointcloud"][start + frame].reshape(-1, 3)


def height_colours(points: np.ndarray) -> np.ndarray:
    """RGB in [0, 1] by height over the cloud's crop box (low: blue, high: red)."""
    height = np.clip((points[:, 2] - CROP_LO[2]) / (CROP_HI[2] - CROP_LO[2]), 0.0, 1.0)
    return np.stack([height, 1.0 - np.abs(height - 0.5), 1.0 - height], axis=-1)


def to_open3d(o3d: ModuleType, points: np.ndarray):
    """An Open3D point cloud of `points`, coloured by height."""
    cloud = o3d.geometry.PointCloud()
    cloud.points = o3d.utility.Vector3dVector(points.astype(np.float64))
    cloud.colors = o3d.utility.Vector3dVector(height_colours(points).astype(np.float64))
    return cloud


def _check(cfg: DictConfig, overrides: list[str]) -> ModuleType:
    """Open3D, `out`/`view`, the display and the source, before anything is built."""
    if cfg.out is None and not cfg.view:
        raise ConfigError("pass out=<file>.ply (and/or view=true on a desktop)")
    if cfg.out is not None and pathlib.Path(str(cfg.out)).suffix != ".ply":
        raise ConfigError(f"out={cfg.out}: must end in .ply")
    if cfg.view and not has_display():
        raise ConfigError("view=true needs a desktop (no DISPLAY here); write out=<file>.ply "
                          "and open it on one")
    o3d = open3d_module()
    if cfg.dataset is None:
        env_kwargs(cfg)
        check_pair(task_class(cfg.task), default_embodiment(cfg))
    elif min(int(cfg.episode), int(cfg.frame)) < 0:
        raise ConfigError("episode and frame must be >= 0")
    return o3d


def _run(cfg: DictConfig, o3d: ModuleType, _out: pathlib.Path | None) -> int:
    if cfg.dataset is None:
        points = env_cloud(cfg)
        title = f"{cfg.task} ({default_embodiment(cfg)}, seed {cfg.seed})"
    else:
        points = dataset_cloud(pathlib.Path(str(cfg.dataset)), int(cfg.episode),
                               int(cfg.frame))
        title = f"{cfg.dataset} episode {cfg.episode} frame {cfg.frame}"
    cloud = to_open3d(o3d, points)
    if cfg.out is not None:
        path = pathlib.Path(str(cfg.out))
        path.parent.mkdir(parents=True, exist_ok=True)
        if not o3d.io.write_point_cloud(str(path), cloud):
            raise ConfigError(f"Open3D could not write {path}")
        print(f"wrote {path} ({len(points)} points: {title})")
    if cfg.view:
        o3d.visualization.draw_geometries([cloud], window_name=title)
    return 0


CLOUD = register(Command("cloud", _run, _check))
cloud = CLOUD.main
