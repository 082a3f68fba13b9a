"""Non-prehensile manipulation: push, slide and topple without grasping."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import objects
from dexbench.assets.objects import ObjectInfo
from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import PushPlan
from dexbench.tasks.templates import Placement, TabletopTask

T_REGION = Placement((-0.41, 0.09), (-0.35, 0.15), (0.0, 2 * math.pi))
GRID_STEP = 0.006  # m, spacing of the points that measure footprint overlap (~500 points)
PUSH_DONE_OVERLAP = 0.95  # the expert stops pushing well inside the 90% success needs


def _goal_pose(env: DexEnv) -> np.ndarray:
    """The sampled planar goal (x, y, yaw) of the pushed block's frame."""
    return env.view.goal[:, :3].cpu().numpy()


def _pushed(env: DexEnv) -> np.ndarray:
    return (env.task.overlap(env.view) >= PUSH_DONE_OVERLAP).cpu().numpy()


def yaw_of(quat: torch.Tensor) -> torch.Tensor:
    """(N,) heading about world z of quaternions (N, 4)."""
    w, x, y, z = quat.unbind(dim=1)
    return torch.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def _rotate2(xy: torch.Tensor, yaw: torch.Tensor) -> torch.Tensor:
    """Rotate points (N, P, 2) by angles (N,)."""
    c, s = torch.cos(yaw)[:, None], torch.sin(yaw)[:, None]
    return torch.stack([c * xy[..., 0] - s * xy[..., 1], s * xy[..., 0] + c * xy[..., 1]], -1)


@register
class PushT(TabletopTask):
    """Overlap is measured on a grid of points covering the goal T's footprint."""

    name = "PushT"
    category = "nonprehensile"
    instruction = "Push the T-shaped block onto the T-shaped target."
    description = ("Push a T-shaped object across the plane until it aligns with the target "
                   "pose.")
    success_text = "The pushed T-shape overlaps at least 90% of the goal T's footprint."
    episode_seconds = 15.0
    placements: ClassVar = {"tee": T_REGION}
    overlap_threshold = 0.90
    expert = PushPlan("tee", objects.T_SHAPE_RECTS, 2 * objects.T_THICKNESS, _goal_pose,
                      _pushed)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        built = {"tee": objects.add_t_shape(spec, "tee"),
                 "goal_tee": objects.add_t_shape(spec, "goal_tee", visual_only=True)}
        self.rects = torch.tensor(objects.T_SHAPE_RECTS, dtype=torch.float64)
        self.grid = self._footprint_grid(self.rects)
        return built

    @staticmethod
    def _footprint_grid(rects: torch.Tensor) -> torch.Tensor:
        """(P, 2) grid points inside the union of rectangles (cx, cy, hx, hy)."""
        lo = (rects[:, :2] - rects[:, 2:]).min(dim=0).values
        hi = (rects[:, :2] + rects[:, 2:]).max(dim=0).values
        xs = torch.arange(lo[0] + GRID_STEP / 2, hi[0], GRID_STEP, dtype=torch.float64)
        ys = torch.arange(lo[1] + GRID_STEP / 2, hi[1], GRID_STEP, dtype=torch.float64)
        pts = torch.cartesian_prod(xs, ys)
        return pts[PushT._inside(pts[None], rects)[0]]

    @staticmethod
    def _inside(pts: torch.Tensor, rects: torch.Tensor) -> torch.Tensor:
        """(N, P) whether points (N, P, 2) lie in the union of rectangles."""
        rel = (pts[:, :, None] - rects[:, :2]).abs()
        return (rel <= rects[:, 2:] + 1e-9).all(dim=-1).any(dim=-1)  # boundary counts

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return np.array([[r.uniform(*T_REGION.x), r.uniform(*T_REGION.y),
                          r.uniform(*T_REGION.yaw)] for r in rngs])

    def sample_reset(self, rngs: list[np.random.Generator]):
        sample = super().sample_reset(rngs)
        goal = sample.goal
        marker = np.zeros((len(rngs), 7))
        marker[:, 0:2] = goal[:, :2]
        marker[:, 2] = TABLE_TOP_Z + self.objects["goal_tee"].rest_height
        marker[:, 3], marker[:, 6] = np.cos(goal[:, 2] / 2), np.sin(goal[:, 2] / 2)
        sample.mocap_poses[self.objects["goal_tee"].root] = marker
        return sample

    def goal_obs(self, view: SceneView) -> torch.Tensor:
        g = view.goal
        return torch.stack([g[:, 0], g[:, 1], torch.cos(g[:, 2]), torch.sin(g[:, 2])], dim=1)

    def overlap(self, view: SceneView) -> torch.Tensor:
        """(N,) fraction of the goal footprint covered by the T."""
        goal = view.goal
        grid = view.constant("PushT/grid", self.grid)[None].expand(len(goal), -1, -1)
        world = _rotate2(grid, goal[:, 2]) + goal[:, None, :2]
        tee = view.body_pos("tee")[:, None, :2]
        local = _rotate2(world - tee, -yaw_of(view.body_quat("tee")))
        rects = view.constant("PushT/rects", self.rects)
        return self._inside(local, rects).to(goal.dtype).mean(dim=1)

    def success(self, view: SceneView) -> torch.Tensor:
        return self.overlap(view) >= self.overlap_threshold

    def progress(self, view: SceneView) -> torch.Tensor:
        return self.overlap(view) / self.overlap_threshold
