"""Small pose utilities experts share: yaw frames and speed-limited motion."""

from __future__ import annotations

import mujoco
import numpy as np

from dexbench.embodiments.builder import HOME_PALM_ROT
from dexbench.embodiments.ik import rotation_angle

# Shared with the plans (`dexbench.tasks.plans`), which need them too.
from dexbench.tasks.plans import body_yaw as body_yaw
from dexbench.tasks.plans import wrap as wrap

# A right hand's handshake pose: fingers +x, palm facing +y, thumb up. A vertical
# cylinder at the grasp offset then lies across the palm, as in a power grasp of a glass.
HANDSHAKE_ROT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def yawed(base: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """(N, 3, 3) hand frames: `base` (3, 3) turned about world z by `yaw` (N,)."""
    c, s = np.cos(yaw), np.sin(yaw)
    rz = np.zeros((len(yaw), 3, 3))
    rz[:, 0, 0], rz[:, 0, 1], rz[:, 1, 0], rz[:, 1, 1], rz[:, 2, 2] = c, -s, s, c, 1.0
    return rz @ base


def palm_down(yaw: np.ndarray) -> np.ndarray:
    """(N, 3, 3) hand frames palm-down with the fingers along world yaw `yaw` (N,)."""
    return yawed(HOME_PALM_ROT, yaw)


def box_yaw(quat: np.ndarray) -> np.ndarray:
    """(N,) yaw of a box about world z, folded into [-pi/4, pi/4] (its 4-fold symmetry)."""
    return (body_yaw(quat) + np.pi / 4) % (np.pi / 2) - np.pi / 4


def pitch_down(angle: float) -> np.ndarray:
    """(3, 3) turn about the hand's y axis tilting the fingers towards the palm side."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def turned(axes: np.ndarray, angle: float | np.ndarray) -> np.ndarray:
    """(N, 3, 3) turns by `angle` (rad; scalar or (N,)) about unit axes (N, 3)."""
    k = np.zeros((len(axes), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axes[:, 2], axes[:, 1], -axes[:, 0]
    k -= k.transpose(0, 2, 1)
    angle = np.broadcast_to(np.asarray(angle, dtype=float), (len(axes),))[:, None, None]
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


TRAVEL_RISE = 0.10  # m a hand rises from where it is before travelling across
ACROSS = 0.03  # m: a target horizontally further than this is travelled to over the top


def via_travel(pos: np.ndarray, target: np.ndarray, travel_z: np.ndarray,
               ) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) waypoints from palms at `pos` to `target` through the height `travel_z`
    (N,): rise in place, cross at that height, come down over the target; and (N,)
    whether each is still rising (it should not turn yet, or it sweeps what is below
    it). A hand going straight would drag its hanging fingers across what lies between."""
    across = np.linalg.norm((pos - target)[:, :2], axis=1) > ACROSS
    low = across & (pos[:, 2] < travel_z - 0.01)
    xy = np.where(low[:, None], pos[:, :2], target[:, :2])
    return np.where(across[:, None], np.column_stack([xy, travel_z]), target), low


def step_towards(pos: np.ndarray, rot: np.ndarray, target_pos: np.ndarray,
                 target_rot: np.ndarray, max_dist: float | np.ndarray, max_angle: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Move poses toward targets by at most `max_dist` (m; scalar or (N, 1)) and
    `max_angle` (rad)."""
    delta = target_pos - pos
    norm = np.linalg.norm(delta, axis=1, keepdims=True)
    new_pos = pos + delta * np.minimum(1.0, max_dist / np.maximum(norm, 1e-9))
    new_rot = rot.copy()
    quat, err, vel = np.zeros(4), np.zeros(4), np.zeros(3)
    for i in range(len(pos)):
        mujoco.mju_mat2Quat(err, (target_rot[i] @ rot[i].T).ravel())
        mujoco.mju_quat2Vel(vel, err, 1.0)
        angle = np.linalg.norm(vel)
        if angle < 1e-9:
            new_rot[i] = target_rot[i]
            continue
        mujoco.mju_axisAngle2Quat(quat, vel / angle, min(angle, max_angle))
        step = np.zeros(9)
        mujoco.mju_quat2Mat(step, quat)
        new_rot[i] = step.reshape(3, 3) @ rot[i]
    return new_pos, new_rot


def way_poses(pos: np.ndarray, rot: np.ndarray, to_pos: np.ndarray, to_rot: np.ndarray,
              count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """`count` palm poses (3,), (3, 3) evenly apart from one pose to another, the last
    that one: an arm's warm-started IK follows a commanded motion step by step, so a
    reach score (`ActionAdapter.reach_cost`) that solves a far pose from the arm's joints
    in one go may find a solution the arm never gets to."""
    here, turn = pos[None], rot[None]
    step = np.linalg.norm(to_pos - pos) / count
    angle = float(rotation_angle(to_rot, rot))
    out = []
    for _ in range(count):
        here, turn = step_towards(here, turn, to_pos[None], to_rot[None], step + 1e-6,
                                  angle / count + 1e-6)
        out.append((here[0], turn[0]))
    return out
