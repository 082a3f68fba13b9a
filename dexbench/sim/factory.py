"""Pick a physics backend by name."""

from __future__ import annotations

import mujoco

from dexbench.sim.backend import SimBackend
from dexbench.sim.cpu import CpuBackend
from dexbench.sim.render import CpuRenderer
from dexbench.sim.warp_render import WarpRenderer

BACKENDS = ("cpu",)
RENDERERS = ("cpu", "warp")


def make_backend(name: str, model: mujoco.MjModel, num_envs: int, nthread: int = 0) -> SimBackend:
    """A backend holding `num_envs` worlds of `model`."""
    if name == "cpu":
        return CpuBackend(model, num_envs, nthread)
    raise ValueError(f"unknown sim backend {name!r}; available: {', '.join(BACKENDS)}")


def make_renderer(backend: SimBackend, width: int, height: int,
                  kind: str = "cpu") -> CpuRenderer | WarpRenderer:
    """A renderer for a backend: `cpu` (OpenGL, `mujoco.Renderer`) or `warp` (ray traced,
    on CUDA when there is a GPU)."""
    if kind not in RENDERERS:
        raise ValueError(f"unknown renderer {kind!r}; available: {', '.join(RENDERERS)}")
    if not isinstance(backend, CpuBackend):
        raise ValueError(f"no renderer for backend {type(backend).__name__}")
    if kind == "warp":
        return WarpRenderer(backend, width, height)
    return CpuRenderer(backend, width, height)
