"""Primitive skills: grasp, lift, place, press, turn."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import torch

from dexbench.assets.objects import add_free_box
from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.task_api import ResetSample, SceneView, Task


def yaw_quat(yaw: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions (w, x, y, z) of rotations about world z."""
    return np.stack([np.cos(yaw / 2), 0 * yaw, 0 * yaw, np.sin(yaw / 2)], axis=-1)


class PickCube(Task):
    """Grasp a cube on the tabletop and lift it at least 0.20 m above its reset height."""

    name = "PickCube"
    category = "primitive"
    instruction = "Pick up the cube and lift it above the table."
    episode_seconds = 20.0
    contact_body = "cube"
    tracked_bodies = ("cube",)

    lift_threshold = 0.20
    half_size = 0.025
    mass = 0.1
    x_range = (-0.10, 0.10)
    y_range = (-0.15, 0.15)

    def build(self, spec: mujoco.MjSpec) -> None:
        add_free_box(spec, "cube", [self.half_size] * 3, self.mass)

    def sample_reset(self, rngs: list[np.random.Generator]) -> ResetSample:
        xy = np.array([[r.uniform(*self.x_range), r.uniform(*self.y_range)] for r in rngs])
        yaw = np.array([r.uniform(-math.pi, math.pi) for r in rngs])
        z = np.full((len(rngs), 1), TABLE_TOP_Z + self.half_size)
        pose = np.concatenate([xy, z, yaw_quat(yaw)], axis=1)
        return ResetSample(free_poses={"cube/free": pose})

    def lift(self, view: SceneView) -> torch.Tensor:
        return view.body_pos("cube")[:, 2] - view.initial_body_pos["cube"][:, 2]

    def success(self, view: SceneView) -> torch.Tensor:
        return self.lift(view) >= self.lift_threshold

    def reward(self, view: SceneView) -> torch.Tensor:
        cube = view.body_pos("cube")
        tip_dist = (view.fingertip_pos() - cube[:, None]).norm(dim=-1).mean(dim=1)
        reach = torch.exp(-10.0 * tip_dist)
        progress = (self.lift(view) / self.lift_threshold).clamp(0.0, 1.0)
        grasping = (tip_dist < 0.08).to(reach.dtype)
        return 2.0 * reach + 2.0 * grasping * progress + 8.0 * self.success(view).to(reach.dtype)

    def state_obs(self, view: SceneView) -> torch.Tensor:
        return torch.cat([view.body_pos("cube"), view.body_quat("cube")], dim=1)

    def privileged_obs(self, view: SceneView) -> torch.Tensor:
        return view.free_joint_vel("cube/free")
