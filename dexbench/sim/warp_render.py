"""GPU rendering: mujoco_warp's ray-traced batch renderer, one launch for every world.

It renders the same cameras as `CpuRenderer` with the same camera model (MuJoCo's
intrinsics and extrinsics, depth to the image plane), so observations do not depend on
the renderer beyond shading. Poses come from the simulator: with the CPU backend the
kinematics every world already computed (geom, camera and light frames) are copied to
the warp device, so no warp physics is compiled; per-world appearance (materials,
colours, light colour, field of view) follows the backend's per-world model fields.
Runs on CUDA, or on warp's CPU device where there is no GPU (slow, but the same code:
the tests use it).
"""

from __future__ import annotations

import mujoco
import numpy as np
import torch

from dexbench.sim.cpu import CpuBackend
from dexbench.sim.render import CameraFrames

# Data frames the renderer reads; the CPU backend has them current after every step.
_POSE_FIELDS = ("geom_xpos", "geom_xmat", "cam_xpos", "cam_xmat", "light_xpos", "light_xdir")
# Model fields visual variation may give each world; the rest are shared.
_APPEARANCE_FIELDS = ("geom_matid", "geom_rgba", "light_diffuse", "cam_fovy")


def _import_warp():
    try:
        import warp

        warp.config.log_level = warp.LOG_WARNING  # before mujoco_warp initialises warp
        import mujoco_warp
    except ImportError as err:
        raise RuntimeError(f"the warp renderer needs mujoco-warp and warp-lang ({err}); "
                           "they are dependencies of dexbench: reinstall it") from None
    return warp, mujoco_warp


def default_warp_device() -> str:
    """CUDA when warp sees a GPU, else warp's CPU device."""
    wp, _ = _import_warp()
    return "cuda:0" if wp.get_cuda_device_count() > 0 else "cpu"


class WarpRenderer:
    """Renders named cameras of every world of a `CpuBackend` with mujoco_warp."""

    def __init__(self, backend: CpuBackend, width: int, height: int,
                 device: str | None = None) -> None:
        self._wp, self._mjw = _import_warp()
        self._backend = backend
        self._model = backend.model
        self.width, self.height = width, height
        self.device = device or default_warp_device()
        # Images go where the simulator's tensors live, so observations share a device.
        self.output_device = backend.device
        self._far = float(self._model.vis.map.zfar * self._model.stat.extent)
        self._poses = {name: backend.batch.bind(name) for name in _POSE_FIELDS}
        with self._wp.ScopedDevice(self.device):
            self._m = self._mjw.put_model(self._model)
            self._d = self._mjw.make_data(self._model, nworld=backend.num_envs)
        self._contexts: dict[tuple, object] = {}

    def _context(self, cameras: tuple[str, ...], rgb: bool, depth: bool):
        """One render context per camera set and output kind, built on first use."""
        key = (cameras, rgb, depth)
        if key not in self._contexts:
            with self._wp.ScopedDevice(self.device):
                self._contexts[key] = self._mjw.create_render_context(
                    self._model, nworld=self._backend.num_envs,
                    cam_res=(self.width, self.height), render_rgb=rgb, render_depth=depth,
                    cam_active=list(cameras), render_skybox=self._has_skybox(),
                    # Rays are built per pixel in the kernel so a per-world field of view
                    # (camera variation) is honoured.
                    use_precomputed_rays=False, use_shadows=True)
        return self._contexts[key]

    def _has_skybox(self) -> bool:
        return bool((self._model.tex_type == mujoco.mjtTexture.mjTEXTURE_SKYBOX).any())

    def _upload(self) -> None:
        """Copy this step's frames (and per-world appearance) onto the warp device."""
        wp = self._wp
        for name, value in self._poses.items():
            dst = getattr(self._d, name)
            src = np.ascontiguousarray(value, dtype=np.float32)
            wp.copy(dst, wp.array(src, dtype=dst.dtype, device=self.device))
        if self._backend.per_world_model:
            for name in _APPEARANCE_FIELDS:
                values = self._backend.batch.expand(name)
                old = getattr(self._m, name)
                setattr(self._m, name, wp.array(np.ascontiguousarray(values),
                                                dtype=old.dtype, device=self.device))

    def render(self, cameras: list[str], rgb: bool, depth: bool) -> dict[str, CameraFrames]:
        wp, mjw = self._wp, self._mjw
        rc = self._context(tuple(cameras), rgb, depth)
        with wp.ScopedDevice(self.device):
            self._upload()
            mjw.refit_bvh(self._m, self._d, rc)
            mjw.render(self._m, self._d, rc)
        n, h, w = self._backend.num_envs, self.height, self.width
        rgb_all = wp.to_torch(rc.rgb_data).view(torch.uint8) if rgb else None
        depth_all = wp.to_torch(rc.depth_data) if depth else None
        rgb_adr, depth_adr = rc.rgb_adr.numpy(), rc.depth_adr.numpy()
        ids = [self._model.camera(c).id for c in cameras]
        fovy = self._backend.batch.expand("cam_fovy") if self._backend.per_world_model \
            else np.broadcast_to(self._model.cam_fovy, (n, self._model.ncam))
        out = {}
        for k, (cam, cid) in enumerate(zip(cameras, ids, strict=True)):
            image = depth_map = None
            if rgb:  # packed little-endian (b, g, r, a) bytes per pixel
                start = 4 * int(rgb_adr[k])
                packed = rgb_all[:, start:start + 4 * h * w].reshape(n, h, w, 4)
                image = packed[..., [2, 1, 0]].to(self.output_device)
            if depth:  # a miss reads 0: report the CPU renderer's far plane instead
                start = int(depth_adr[k])
                raw = depth_all[:, start:start + h * w].reshape(n, h, w)
                depth_map = torch.where(raw > 0, raw, self._far).to(self.output_device)
            out[cam] = CameraFrames(
                image, depth_map,
                torch.from_numpy(np.array(self._poses["cam_xpos"][:, cid])),
                torch.from_numpy(np.array(self._poses["cam_xmat"][:, cid]).reshape(n, 3, 3)),
                torch.from_numpy(np.array(fovy[:, cid], dtype=np.float64)))
        return out

    def close(self) -> None:
        self._contexts.clear()
