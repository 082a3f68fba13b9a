"""Task thumbnails for `docs/tasks.md`: each task's scene right after reset, so a reader
sees the objects next to the success condition.

The front camera of the task's default embodiment (seed 0, nominal visuals), cropped to
the table, written as `docs/img/tasks/<Task>.png`.
"""

from __future__ import annotations

import pathlib

import numpy as np
from PIL import Image

from dexbench.tasks.registry import TASKS, make_gym_env

RENDER_SIZE = (480, 360)  # (width, height) rendered, before the crop
CROP = (0.06, 0.12, 0.94, 0.86)  # left, top, right, bottom as fractions: the table
THUMB_WIDTH = 320


def thumbnail(task: str) -> Image.Image:
    """The task's scene after `reset(seed=0)`, from the front camera, table-cropped."""
    env = make_gym_env(task, render_mode="rgb_array", render_size=RENDER_SIZE)
    try:
        env.reset(seed=0)
        frame: np.ndarray = env.render()
    finally:
        env.close()
    w, h = RENDER_SIZE
    box = (round(CROP[0] * w), round(CROP[1] * h), round(CROP[2] * w), round(CROP[3] * h))
    image = Image.fromarray(frame).crop(box)
    height = round(THUMB_WIDTH * image.height / image.width)
    return image.resize((THUMB_WIDTH, height), Image.Resampling.LANCZOS)


def write_thumbnails(folder: pathlib.Path) -> dict[str, pathlib.Path]:
    """One PNG per registered task in `folder` (each via a temp file, then renamed)."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name in TASKS:
        path = folder / f"{name}.png"
        tmp = path.with_name(f".{path.name}.tmp")
        thumbnail(name).save(tmp, format="PNG", optimize=True)
        tmp.replace(path)
        paths[name] = path
    return paths
