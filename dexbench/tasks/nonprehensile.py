"""Non-prehensile manipulation: push, slide and topple without grasping."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import objects, ramps
from dexbench.assets.objects import ObjectInfo
from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import PathPushPlan, PushPlan
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


BALL_START = (0.04, 0.08)  # m before the ramp's foot, along its uphill axis
BALL_SIDE = 0.03  # m either side of its centre line
BALL_FRICTION = 0.4  # hard plastic: a fingertip pushing it slides rather than jams it
PAST_CREST = 0.05  # m: the expert stops pushing once the ball is this far past the crest


def _ramp_path(env: DexEnv) -> np.ndarray:
    """(N, 2, 3) the ramp's centre line, from its foot to beyond its crest."""
    task = env.task
    uphill = env.view.axis(*task.objects["ramp"].axes["uphill"]).cpu().numpy()
    foot = task.point(env.view, "ramp", "foot").cpu().numpy()
    crest = task.point(env.view, "ramp", "target").cpu().numpy()
    return np.stack([foot - 0.1 * uphill, crest + PAST_CREST * uphill], axis=1)


def _over_crest(env: DexEnv) -> np.ndarray:
    return (env.task.past(env.view) >= PAST_CREST).cpu().numpy() & env.task.success(
        env.view).cpu().numpy()


@register
class PushSmallSphereObstacleSlope(TabletopTask):
    """The ramp stands at a random pose; two obstacle pairs at two of its five slots."""

    name = "PushSmallSphereObstacleSlope"
    category = "nonprehensile"
    instruction = "Push the small ball up the ramp, between the posts, over its top."
    description = ("Push a small sphere uphill through randomly spawned obstacles until it "
                   "crosses the target line.")
    success_text = ("The sphere crosses the target line, reaching or passing both the "
                    "target's forward position and height.")
    deviations = ("The authors give no reset ranges beyond the obstacles: the ramp's pose "
                  "(x 0.05..0.10, y -0.10..0.10, yaw -0.2..0.2) and the ball's start "
                  "(4-8 cm before the ramp's foot, within 3 cm of its centre line) are ours.",
                  f"The ball is hard plastic (friction {BALL_FRICTION}, also against the "
                  "hand): at the default 1.0 a fingertip pushing it jams it against the "
                  "slope instead of sliding on it.")
    placements: ClassVar = {"ramp": Placement((0.05, 0.10), (-0.10, 0.10), (-0.2, 0.2))}
    pairs = 2
    expert = PathPushPlan("sphere", _ramp_path, _over_crest)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        built = {"sphere": objects.add_sphere(spec, "sphere", radius=0.02,
                                              friction=(BALL_FRICTION, 0.005, 0.0001)),
                 "ramp": ramps.add_ramp(spec, "ramp")}
        spec.geom("sphere/geom").priority = 1  # its friction, not the larger one, holds
        for k in range(self.pairs):
            built[f"posts{k}"] = ramps.add_obstacle_pair(spec, f"posts{k}")
        return built

    def sample_reset(self, rngs: list[np.random.Generator]):
        sample = super().sample_reset(rngs)
        ramp = sample.mocap_poses["ramp"]
        yaw = 2 * np.arctan2(ramp[:, 6], ramp[:, 3])
        rot = np.stack([np.cos(yaw), -np.sin(yaw), np.sin(yaw), np.cos(yaw)], 1).reshape(-1, 2, 2)
        points = self.objects["ramp"].points

        def world(local: np.ndarray) -> np.ndarray:
            out = ramp[:, :3].copy()
            out[:, :2] += np.einsum("nij,nj->ni", rot, local[:, :2])
            out[:, 2] += local[:, 2]
            return out

        slots = np.array([r.choice(len(ramps.SLOTS), self.pairs, replace=False) for r in rngs])
        for k in range(self.pairs):
            local = np.array([points[f"slot{i}"][1] for i in slots[:, k]])
            sample.mocap_poses[f"posts{k}"] = np.concatenate([world(local), ramp[:, 3:]], 1)
        foot = np.array(points["foot"][1])
        ball = np.array([foot - [r.uniform(*BALL_START), r.uniform(-BALL_SIDE, BALL_SIDE), 0.0]
                         for r in rngs])
        ball = world(ball)
        ball[:, 2] = TABLE_TOP_Z + self.objects["sphere"].rest_height
        sample.free_poses["sphere/free"] = np.concatenate(
            [ball, np.tile([1.0, 0.0, 0.0, 0.0], (len(rngs), 1))], 1)
        return sample

    def past(self, view: SceneView) -> torch.Tensor:
        """(N,) how far (m) the ball's centre is past the crest, uphill."""
        uphill = view.axis(*self.objects["ramp"].axes["uphill"])
        off = view.body_pos("sphere") - self.point(view, "ramp", "target")
        return (off * uphill).sum(dim=1)

    def success(self, view: SceneView) -> torch.Tensor:
        high = view.body_pos("sphere")[:, 2] >= self.point(view, "ramp", "target")[:, 2]
        return (self.past(view) >= 0.0) & high

    def progress(self, view: SceneView) -> torch.Tensor:
        foot = self.point(view, "ramp", "foot")
        crest = self.point(view, "ramp", "target")
        run = (crest - foot)[:, :2].norm(dim=1)
        return 1.0 + self.past(view).clamp(max=0.0) / (run + 0.1)
