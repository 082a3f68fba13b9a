"""Pick a physics backend by name."""

from __future__ import annotations

import mujoco

from dexbench.sim.backend import SimBackend
from dexbench.sim.cpu import CpuBackend
from dexbench.sim.render import CpuRenderer
from dexbench.sim.warp_render import WarpRenderer

BACKENDS = ("cpu", "warp")
RENDERERS = ("cpu", "warp")


def make_backend(name: str, model: mujoco.MjModel, num_envs: int, nthread: int = 0,
                 nconmax: int | None = None, njmax: int | None = None) -> SimBackend:
    """A backend holding `num_envs` worlds of `model`: `cpu` (mujoco.batch on `nthread`
    threads) or `warp` (mujoco_warp on the GPU, warp's CPU device without one;
    `nconmax`/`njmax` override its per-world contact and constraint capacity)."""
    if name == "cpu":
        return CpuBackend(model, num_envs, nthread)
    if name == "warp":
        from dexbench.sim.warp import WarpBackend  # imports warp only when asked for

        return WarpBackend(model, num_envs, nconmax=nconmax, njmax=njmax)
    raise ValueError(f"unknown sim backend {name!r}; available: {', '.join(BACKENDS)}")


def make_renderer(backend: SimBackend, width: int, height: int, kind: str = "cpu",
                  shadows: bool = True) -> CpuRenderer | WarpRenderer:
    """A renderer for a backend: `cpu` (OpenGL, `mujoco.Renderer`; CPU backend only) or
    `warp` (ray traced, on CUDA when there is a GPU; the warp backend's own arrays).
    `shadows` off skips the lights' shadows (the ray tracer then casts one ray per pixel
    instead of two)."""
    if kind not in RENDERERS:
        raise ValueError(f"unknown renderer {kind!r}; available: {', '.join(RENDERERS)}")
    if kind == "warp":
        return WarpRenderer(backend, width, height, shadows=shadows)
    if not isinstance(backend, CpuBackend):
        raise ValueError(f"the cpu renderer needs the cpu backend; with "
                         f"{type(backend).__name__} use camera.renderer=warp")
    return CpuRenderer(backend, width, height, shadows)
