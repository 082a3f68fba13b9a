"""`python -m dexbench snapshot task=<T> embodiment=<E> visual=<preset>`: a contact sheet.

One row per environment (labelled `env <k>`), one column per image, each headed by its
modality and camera: every camera's RGB, the front depth (near = bright) and the fused
point cloud seen from above (colour = height). Written as a PNG under `runs/snapshot/`,
for humans to check a scene, its cameras and its variation.
"""

from __future__ import annotations

import pathlib

import numpy as np
import torch
from omegaconf import DictConfig
from PIL import Image, ImageDraw, ImageFont

from dexbench.cli.app import Command, register, stamp
from dexbench.cli.config import default_embodiment, env_kwargs, load_config, open_run_dir
from dexbench.envs.arena import TABLE_HALF_SIZE
from dexbench.envs.camera_obs import CROP_HI, CROP_LO, THIRD_PERSON
from dexbench.envs.scene import check_pair
from dexbench.tasks.registry import make_env, task_class

FONT_PX = 12
LINE_PX = FONT_PX + 3
HEADER_PX = 2 * LINE_PX + 4  # two lines: modality, then camera
ROW_LABEL_PX = 44
GAP_PX = 2
BACKGROUND, INK = (255, 255, 255), (20, 20, 20)


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


def _camera_label(camera: str) -> str:
    """`right/hand/wrist_cam` -> `right wrist`; third-person cameras keep their name."""
    side, _, rest = camera.partition("/hand/")
    return f"{side} wrist" if rest == "wrist_cam" else camera


def column_labels(cameras: list[str]) -> list[tuple[str, str]]:
    """(modality, camera) over each column of the sheet, left to right."""
    return ([("rgb", _camera_label(c)) for c in cameras]
            + [("depth", "front, near = bright"), ("point cloud", "top view, colour = height")])


def _cell(lines: tuple[str, ...], size: tuple[int, int], font) -> Image.Image:
    """A label cell; text wider than the cell is cut at its edge, never spills over."""
    cell = Image.new("RGB", size, BACKGROUND)
    draw = ImageDraw.Draw(cell)
    for i, line in enumerate(lines):
        draw.text((3, 2 + i * LINE_PX), line, fill=INK, font=font)
    return cell


def contact_sheet(rows: list[list[np.ndarray]], labels: list[tuple[str, str]]) -> Image.Image:
    """Tiles (rows x columns, equal sizes, `GAP_PX` apart) under a header of `labels`,
    each row labelled `env <k>`."""
    h, w = rows[0][0].shape[:2]
    font = ImageFont.load_default(size=FONT_PX)
    step_x, step_y = w + GAP_PX, h + GAP_PX
    sheet = Image.new("RGB", (ROW_LABEL_PX + step_x * len(labels) - GAP_PX,
                              HEADER_PX + step_y * len(rows) - GAP_PX), BACKGROUND)
    for j, label in enumerate(labels):
        sheet.paste(_cell(label, (w, HEADER_PX), font), (ROW_LABEL_PX + j * step_x, 0))
    for i, tiles in enumerate(rows):
        top = HEADER_PX + i * step_y
        sheet.paste(_cell((f"env {i}",), (ROW_LABEL_PX, h), font), (0, top))
        for j, tile in enumerate(tiles):
            sheet.paste(Image.fromarray(tile), (ROW_LABEL_PX + j * step_x, top))
    return sheet


def snapshot(overrides: list[str]) -> str:
    """Programmatic `python -m dexbench snapshot ...`: the PNG's path."""
    cfg = load_config("snapshot", overrides)
    env_kwargs(cfg)
    return snapshot_in(cfg, SNAPSHOT.folder(cfg, stamp()))


def snapshot_in(cfg: DictConfig, out: pathlib.Path) -> str:
    kwargs = env_kwargs(cfg)
    embodiment_env = make_env(**{**kwargs, "num_envs": 1})
    wrists = [f"{side}/hand/wrist_cam" for side in embodiment_env.embodiment.sides]
    cameras = [*THIRD_PERSON, *wrists]
    kwargs.update(obs=["rgb", "depth", "pointcloud"], cameras=cameras)
    env = make_env(**kwargs)
    obs = {k: v.numpy() if isinstance(v, torch.Tensor) else v for k, v in env.reset().items()}
    size = (int(cfg.camera.width), int(cfg.camera.height))
    rows = [[*(obs[f"rgb/{c}"][e] for c in cameras), _depth_image(obs["depth/front"][e]),
             _cloud_image(obs["pointcloud"][e], size)] for e in range(env.num_envs)]
    sheet = contact_sheet(rows, column_labels(cameras))
    run_dir = open_run_dir(out, cfg)
    path = run_dir / "snapshot.png"
    tmp = run_dir / ".snapshot.png.tmp"
    sheet.save(tmp, format="PNG")
    tmp.replace(path)
    return str(path)


def _check(cfg: DictConfig, overrides: list[str]) -> None:
    env_kwargs(cfg)
    check_pair(task_class(cfg.task), default_embodiment(cfg))


def _run(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    print(f"wrote {snapshot_in(cfg, out)}")
    return 0


def _dir(cfg: DictConfig) -> tuple[str, str]:
    return "snapshot", f"{{stamp}}-{cfg.task}-{default_embodiment(cfg)}"


SNAPSHOT = register(Command("snapshot", _run, _check, _dir))
