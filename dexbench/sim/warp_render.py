"""GPU rendering: mujoco_warp's ray-traced batch renderer, one launch for every world.

It renders the same cameras as `CpuRenderer` with the same camera model (MuJoCo's
intrinsics and extrinsics, depth to the image plane), so observations do not depend on
the renderer beyond shading. Poses come from the simulator: with the CPU backend the
kinematics every world already computed (geom, camera and light frames) are copied to
the warp device, so no warp physics is compiled; per-world appearance (materials,
colours, light colour, field of view) follows the backend's per-world model fields.
Runs on CUDA, or on warp's CPU device where there is no GPU (slow, but the same code:
the tests use it). With the warp backend it renders the simulator's own arrays: nothing
is copied and appearance follows its per-world model fields directly.
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
    """Renders named cameras of every world of a `CpuBackend` or a `WarpBackend` with
    mujoco_warp."""

    def __init__(self, backend, width: int, height: int, device: str | None = None,
                 shadows: bool = True) -> None:
        self._wp, self._mjw = _import_warp()
        self._backend = backend
        self._model = backend.model
        self.width, self.height = width, height
        self.shadows = shadows
        # Images go where the simulator's tensors live, so observations share a device.
        self.output_device = backend.device
        self._far = float(self._model.vis.map.zfar * self._model.stat.extent)
        self._contexts: dict[tuple, object] = {}
        self._shared = not isinstance(backend, CpuBackend)
        if self._shared:  # a WarpBackend: its model and data, current after every step
            self.device = backend.wp_device
            self._m, self._d = backend.m, backend.d
            self._poses = {name: self._wp.to_torch(getattr(self._d, name))
                           for name in ("cam_xpos", "cam_xmat")}
            return
        self.device = device or default_warp_device()
        self._poses = {name: backend.batch.bind(name) for name in _POSE_FIELDS}
        with self._wp.ScopedDevice(self.device):
            self._m = self._mjw.put_model(self._model)
            self._d = self._mjw.make_data(self._model, nworld=backend.num_envs)

    def _context(self, cameras: tuple[str, ...], rgb: bool, depth: bool):
        """One render context per camera set and output kind, built on first use, with
        each camera's offsets into its image buffers (read once: a read from the GPU
        would stall the host every frame)."""
        key = (cameras, rgb, depth)
        if key not in self._contexts:
            with self._wp.ScopedDevice(self.device):
                rc = self._mjw.create_render_context(
                    self._model, nworld=self._backend.num_envs,
                    cam_res=(self.width, self.height), render_rgb=rgb, render_depth=depth,
                    cam_active=list(cameras), render_skybox=self._has_skybox(),
                    # Rays are built per pixel in the kernel so a per-world field of view
                    # (camera variation) is honoured.
                    use_precomputed_rays=False, use_shadows=self.shadows)
            self._contexts[key] = (rc, rc.rgb_adr.numpy(), rc.depth_adr.numpy())
        return self._contexts[key]

    def _has_skybox(self) -> bool:
        return bool((self._model.tex_type == mujoco.mjtTexture.mjTEXTURE_SKYBOX).any())

    def _upload(self) -> None:
        """Copy this step's frames (and per-world appearance) onto the warp device."""
        wp = self._wp
        if self._shared:
            return
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

    def render(self, cameras: list[str], rgb: bool, depth: bool,
               envs: np.ndarray | None = None) -> dict[str, CameraFrames]:
        """Every world's frames; one batched ray-tracing pass draws all worlds, so `envs`
        (the worlds whose frames are read) saves nothing here and is accepted for the
        renderers' common interface."""
        wp, mjw = self._wp, self._mjw
        rc, rgb_adr, depth_adr = self._context(tuple(cameras), rgb, depth)
        with wp.ScopedDevice(self.device):
            self._upload()
            mjw.refit_bvh(self._m, self._d, rc)
            mjw.render(self._m, self._d, rc)
            if self._shared and self.device != "cpu":  # torch reads the images next
                torch_stream = wp.stream_from_torch(torch.cuda.current_stream(self.device))
                torch_stream.wait_stream(wp.get_stream())
        n, h, w = self._backend.num_envs, self.height, self.width
        rgb_all = wp.to_torch(rc.rgb_data).view(torch.uint8) if rgb else None
        depth_all = wp.to_torch(rc.depth_data) if depth else None
        ids = [self._model.camera(c).id for c in cameras]
        fovy = self._fovy(n)
        out = {}
        for k, (cam, cid) in enumerate(zip(cameras, ids, strict=True)):
            image = depth_map = None
            if rgb:  # packed little-endian (b, g, r, a) bytes per pixel
                start = 4 * int(rgb_adr[k])
                packed = rgb_all[:, start:start + 4 * h * w].reshape(n, h, w, 4)
                image = packed[..., :3].flip(-1).to(self.output_device)
            if depth:  # a miss reads 0: report the CPU renderer's far plane instead
                start = int(depth_adr[k])
                raw = depth_all[:, start:start + h * w].reshape(n, h, w)
                depth_map = torch.where(raw > 0, raw, self._far).to(self.output_device)
            pos, mat = self._poses["cam_xpos"][:, cid], self._poses["cam_xmat"][:, cid]
            out[cam] = CameraFrames(
                image, depth_map, torch.as_tensor(np.array(pos) if not self._shared
                                                  else pos.double()),
                torch.as_tensor(np.array(mat) if not self._shared
                                else mat.double()).reshape(n, 3, 3),
                torch.as_tensor(fovy[:, cid]).double())
        return out

    def _fovy(self, n: int):
        """(n, ncam) field of view of every world's cameras, degrees."""
        if self._shared:
            return self._wp.to_torch(self._m.cam_fovy).expand(n, -1)
        if self._backend.per_world_model:
            return np.array(self._backend.batch.expand("cam_fovy"))
        return np.broadcast_to(self._model.cam_fovy, (n, self._model.ncam)).copy()

    def close(self) -> None:
        self._contexts.clear()
