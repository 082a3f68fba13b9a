"""Camera observation groups: rgb and depth per camera, and the fused point cloud.

Keys are `rgb/<camera>` (uint8, (N, H, W, 3)), `depth/<camera>` (float32 metres,
(N, H, W)) and `pointcloud` (float32 world frame, (N, num_points, 3)): the third-person
cameras' depth back-projected, cropped to the table volume (+0.01..+0.60 m above the
top), thinned evenly and farthest-point sampled.
"""

from __future__ import annotations

import torch

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.arena import CAMERAS, TABLE_HALF_SIZE
from dexbench.envs.pointcloud import crop_mask, depth_to_world, sample_cloud

THIRD_PERSON = tuple(name for name, _, _ in CAMERAS)
SINGLE_VIEW = ("front",)
# The paper fuses two views into a bimanual task's point cloud: the side cameras, each
# facing one hand, so that neither hand hides the object from the cloud.
BIMANUAL_CLOUD = ("left", "right")
CROP_LO = (-TABLE_HALF_SIZE[0], -TABLE_HALF_SIZE[1], TABLE_TOP_Z + 0.01)
CROP_HI = (TABLE_HALF_SIZE[0], TABLE_HALF_SIZE[1], TABLE_TOP_Z + 0.60)


def default_cameras(multiview: bool, groups: tuple[str, ...] = (), arity: int = 1
                    ) -> tuple[str, ...]:
    """The paper's cameras: the front view, or the three third-person views; a
    single-view point cloud on two hands fuses the two side views."""
    if multiview:
        return THIRD_PERSON
    return BIMANUAL_CLOUD if arity == 2 and "pointcloud" in groups else SINGLE_VIEW


class CameraObservations:
    """Renders once per observation and derives every requested camera group."""

    def __init__(self, renderer, cameras: tuple[str, ...], groups: tuple[str, ...],
                 num_points: int, cloud_device: str | None = None) -> None:
        self.renderer = renderer
        # Back-projecting, cropping and sampling dozens of depth images per step is the
        # CPU renderer's bottleneck; on a GPU it takes a few milliseconds. None: where the
        # renderer leaves the images.
        self.cloud_device = None if cloud_device is None else torch.device(cloud_device)
        self.cameras = cameras
        self.groups = groups
        self.num_points = num_points
        self.cloud_cameras = tuple(c for c in cameras if c in THIRD_PERSON)
        if "pointcloud" in groups and not self.cloud_cameras:
            raise ValueError(f"pointcloud needs one of the cameras {THIRD_PERSON}")

    def compute(self, envs: torch.Tensor | None = None) -> dict[str, torch.Tensor]:
        """Every env's camera groups, or only those of `envs` (indices): the other envs'
        rows are zero, for a reader that will not look at them this step."""
        want_depth = "depth" in self.groups or "pointcloud" in self.groups
        frames = self.renderer.render(list(self.cameras), rgb="rgb" in self.groups,
                                       depth=want_depth,
                                       envs=None if envs is None else envs.cpu().numpy())
        out: dict[str, torch.Tensor] = {}
        for cam, f in frames.items():
            if "rgb" in self.groups:
                out[f"rgb/{cam}"] = f.rgb
            if "depth" in self.groups:
                out[f"depth/{cam}"] = f.depth
        if "pointcloud" in self.groups:
            home = frames[self.cloud_cameras[0]].depth.device
            at = self.cloud_device or home
            if envs is None:
                out["pointcloud"] = self._clouds(frames, slice(None), at).to(home)
            else:
                n = frames[self.cloud_cameras[0]].depth.shape[0]
                cloud = torch.zeros(n, self.num_points, 3, device=home)
                if len(envs):
                    rows = envs.to(home)
                    cloud.index_copy_(0, rows, self._clouds(frames, rows, at).to(home))
                out["pointcloud"] = cloud
        return out

    def _clouds(self, frames, rows, at: torch.device) -> torch.Tensor:
        """(len(rows), num_points, 3) float32 fused clouds of those envs, computed on `at`."""
        clouds = [depth_to_world(f.depth[rows].to(at), f.fovy[rows].to(at),
                                 f.cam_pos[rows].to(at), f.cam_mat[rows].to(at))
                  for f in (frames[c] for c in self.cloud_cameras)]
        points = torch.cat(clouds, dim=1)
        cloud = sample_cloud(points, crop_mask(points, CROP_LO, CROP_HI), self.num_points)
        return cloud.to(torch.float32)
