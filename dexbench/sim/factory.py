"""Pick a physics backend by name."""

from __future__ import annotations

import mujoco

from dexbench.sim.backend import SimBackend
from dexbench.sim.cpu import CpuBackend
from dexbench.sim.render import CpuRenderer

BACKENDS = ("cpu",)


def make_backend(name: str, model: mujoco.MjModel, num_envs: int, nthread: int = 0) -> SimBackend:
    """A backend holding `num_envs` worlds of `model`."""
    if name == "cpu":
        return CpuBackend(model, num_envs, nthread)
    raise ValueError(f"unknown sim backend {name!r}; available: {', '.join(BACKENDS)}")


def make_renderer(backend: SimBackend, width: int, height: int) -> CpuRenderer:
    """The renderer that matches a backend."""
    if isinstance(backend, CpuBackend):
        return CpuRenderer(backend, width, height)
    raise ValueError(f"no renderer for backend {type(backend).__name__}")
