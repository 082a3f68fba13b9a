"""CPU rendering: `mujoco.Renderer` (EGL or OSMesa, headless) over the CPU backend.

Each environment's state is copied into one scratch MjData (`Batch.get_data`) and,
when visual variation gives worlds their own colours, lights or cameras, its model into
one scratch MjModel; the scene is then rendered from each camera. RGB is uint8, depth
is metres along the camera axis (distance to the image plane); camera poses come back
with the images so depth can be turned into world points.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import mujoco
import numpy as np
import torch

from dexbench.sim.cpu import CpuBackend


@dataclass
class CameraFrames:
    """One camera's images for every environment."""

    rgb: torch.Tensor | None  # (N, H, W, 3) uint8
    depth: torch.Tensor | None  # (N, H, W) float32, metres
    cam_pos: torch.Tensor  # (N, 3) float64, world
    cam_mat: torch.Tensor  # (N, 3, 3) float64, camera axes as columns (looks along -z)
    fovy: torch.Tensor  # (N,) vertical field of view, degrees (varies per world)


class CpuRenderer:
    """Renders named cameras of every world of a `CpuBackend`."""

    def __init__(self, backend: CpuBackend, width: int, height: int,
                 shadows: bool = True) -> None:
        self._backend = backend
        self._model = backend.model
        self.width, self.height = width, height
        self.shadows = shadows
        try:
            self._renderer = mujoco.Renderer(self._model, height=height, width=width)
        except (mujoco.FatalError, RuntimeError) as err:
            raise RuntimeError(
                f"cannot create an offscreen OpenGL context ({err}); headless machines "
                "need MUJOCO_GL=egl (libEGL) or MUJOCO_GL=osmesa set before mujoco is "
                "first imported (importing dexbench first sets egl by default)") from None
        self._renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = shadows
        self._data = mujoco.MjData(self._model)
        self._world_model = copy.copy(self._model)  # scratch for per-world fields
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
    def render(self, cameras: list[str], rgb: bool, depth: bool,
               envs: np.ndarray | None = None) -> dict[str, CameraFrames]:
        """Every world's frames, or only those of `envs` (indices): the others stay zero
        (camera poses included), and rendering costs in proportion to the worlds drawn."""
        n, model = self._backend.num_envs, self._model
        h, w = self.height, self.width
        ids = [model.camera(c).id for c in cameras]
        out_rgb = np.zeros((len(cameras), n, h, w, 3), np.uint8) if rgb else None
        out_depth = np.zeros((len(cameras), n, h, w), np.float32) if depth else None
        pos = np.zeros((len(cameras), n, 3))
        mat = np.zeros((len(cameras), n, 3, 3))
        fovy = np.zeros((len(cameras), n))
        r = self._renderer
        for env in (range(n) if envs is None else envs):
            env = int(env)
            self._backend.batch.get_data(env, self._data)
            model = self._backend.world_model(env, self._world_model)
            for k, cam in enumerate(ids):
                pos[k, env] = self._data.cam_xpos[cam]
                mat[k, env] = self._data.cam_xmat[cam].reshape(3, 3)
                fovy[k, env] = model.cam_fovy[cam]
                self._camera.fixedcamid = cam
                mujoco.mjv_updateScene(model, self._data, self._option, None, self._camera,
                                       mujoco.mjtCatBit.mjCAT_ALL.value, r.scene)
                if rgb:
                    out_rgb[k, env] = r.render()
                if depth:
                    r.enable_depth_rendering()
                    out_depth[k, env] = r.render()
                    r.disable_depth_rendering()
        return {
            cam: CameraFrames(
                torch.from_numpy(out_rgb[k]) if rgb else None,
                torch.from_numpy(out_depth[k]) if depth else None,
                torch.from_numpy(pos[k]), torch.from_numpy(mat[k]), torch.from_numpy(fovy[k]))
            for k, cam in enumerate(cameras)
        }

    def close(self) -> None:
        self._renderer.close()
