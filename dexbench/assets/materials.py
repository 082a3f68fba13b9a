"""A library of procedural materials (textures built by MuJoCo's builtins, no files).

Visual variation switches geoms between these materials per environment, which needs no
texture upload at render time. Even indices form the `train` appearance pool, odd ones
the `test` pool, so appearances seen in evaluation can be kept out of training.
"""

from __future__ import annotations

import colorsys

import mujoco
import numpy as np

NUM_MATERIALS = 16
_PATTERNS = ("flat", "checker", "gradient", "noise")


def _rgb(rng: np.random.Generator, light: tuple[float, float]) -> list[float]:
    return list(colorsys.hsv_to_rgb(rng.uniform(), rng.uniform(0.2, 0.7), rng.uniform(*light)))


def add_material_library(spec: mujoco.MjSpec, prefix: str = "var") -> list[str]:
    """Add NUM_MATERIALS textured materials named `<prefix>/mat<i>`; return their names.

    Patterns cycle through flat colour, checker, gradient (wood/stone-like banding) and
    random-speckle noise; colours and surface parameters come from a fixed seed so every
    machine builds the same library.
    """
    rng = np.random.default_rng(2026)
    names = []
    for i in range(NUM_MATERIALS):
        pattern = _PATTERNS[i % len(_PATTERNS)]
        tex = spec.add_texture(name=f"{prefix}/tex{i}", type=mujoco.mjtTexture.mjTEXTURE_2D,
                               width=64, height=64, rgb1=_rgb(rng, (0.4, 0.9)),
                               rgb2=_rgb(rng, (0.2, 0.7)))
        if pattern == "flat":
            tex.builtin = mujoco.mjtBuiltin.mjBUILTIN_FLAT
        elif pattern == "checker":
            tex.builtin = mujoco.mjtBuiltin.mjBUILTIN_CHECKER
        elif pattern == "gradient":
            tex.builtin = mujoco.mjtBuiltin.mjBUILTIN_GRADIENT
        else:
            tex.builtin = mujoco.mjtBuiltin.mjBUILTIN_FLAT
            tex.mark = mujoco.mjtMark.mjMARK_RANDOM
            tex.random = 0.3
            tex.markrgb = _rgb(rng, (0.1, 0.5))
        mat = spec.add_material(name=f"{prefix}/mat{i}", specular=float(rng.uniform(0, 0.6)),
                                shininess=float(rng.uniform(0, 0.8)),
                                texrepeat=[4.0, 4.0], texuniform=True)
        mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = tex.name
        names.append(mat.name)
    return names


def pool(split: str) -> list[int]:
    """Library indices of an appearance pool: `train` (even) or `test` (odd)."""
    if split not in ("train", "test"):
        raise ValueError(f"appearance split must be 'train' or 'test', got {split!r}")
    return list(range(0 if split == "train" else 1, NUM_MATERIALS, 2))
