"""Damped least-squares inverse kinematics for a site, within joint limits.

Used to find arm home poses at build time and by experts and tests to reach targets.
Works on any compiled model; only the listed joints move.
"""

from __future__ import annotations

import mujoco
import numpy as np


def solve_site_pose(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    site: str,
    joints: list[str],
    target_pos: np.ndarray,
    target_rot: np.ndarray | None = None,
    iterations: int = 300,
    damping: float = 1e-3,
    tol: float = 1e-4,
) -> tuple[np.ndarray, float]:
    """Move `joints` in `data.qpos` so `site` reaches the target; return (qpos, error).

    Position error is in metres; with a target rotation, the orientation error (rad) is
    added with weight 0.1 m/rad. Joint limits are enforced every iteration.
    """
    sid = model.site(site).id
    jids = [model.joint(j).id for j in joints]
    qadr = np.array([model.jnt_qposadr[j] for j in jids])
    dadr = np.array([model.jnt_dofadr[j] for j in jids])
    lo = np.where(model.jnt_limited[jids], model.jnt_range[jids, 0], -np.inf)
    hi = np.where(model.jnt_limited[jids], model.jnt_range[jids, 1], np.inf)
    jacp = np.zeros((3, model.nv))
    jacr = np.zeros((3, model.nv))
    err = np.inf
    for _ in range(iterations):
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        e_pos = target_pos - data.site_xpos[sid]
        rows = [e_pos]
        mujoco.mj_jacSite(model, data, jacp, jacr, sid)
        jac = [jacp[:, dadr]]
        if target_rot is not None:
            cur = data.site_xmat[sid].reshape(3, 3)
            e_rot = _rotation_error(cur, target_rot)
            rows.append(0.1 * e_rot)
            jac.append(0.1 * jacr[:, dadr])
        e = np.concatenate(rows)
        err = float(np.linalg.norm(e))
        if err < tol:
            break
        j = np.vstack(jac)
        dq = j.T @ np.linalg.solve(j @ j.T + damping * np.eye(j.shape[0]), e)
        data.qpos[qadr] = np.clip(data.qpos[qadr] + dq, lo, hi)
    return data.qpos[qadr].copy(), err


def _rotation_error(current: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Axis-angle vector (world frame) rotating `current` onto `target`."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (target @ current.T).ravel())
    vel = np.zeros(3)
    mujoco.mju_quat2Vel(vel, quat, 1.0)
    return vel
