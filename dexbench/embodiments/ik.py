"""Damped least-squares inverse kinematics for a site, within joint limits.

Used to find arm home poses at build time and by experts and tests to reach targets.
Works on any compiled model; only the listed joints move.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

# The residuals at which a palm pose counts as not taken, for the matrix's feasibility test
# (`dexbench.eval.feasibility`) and the experts' reach scores (`ActionAdapter.reach_cost`).
POS_TOL = 0.02  # m: about a fingertip's width, below any grasp's margin
ROT_TOL = 0.25  # rad (~14 deg): beyond it a pose counts as not taken (pose-limited)


def rotation_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(...) angle (rad) of the turn between rotation matrices `a` and `b` (..., 3, 3)."""
    cos = (np.einsum("...ij,...ij->...", a, b) - 1.0) / 2.0
    return np.arccos(np.clip(cos, -1.0, 1.0))


def pose_residual(model: mujoco.MjModel, data: mujoco.MjData, site: int, pos: np.ndarray,
                  rot: np.ndarray) -> tuple[float, float]:
    """(position m, orientation rad) between site `site` at `data.qpos` and a pose."""
    mujoco.mj_kinematics(model, data)
    return (float(np.linalg.norm(pos - data.site_xpos[site])),
            float(rotation_angle(rot, data.site_xmat[site].reshape(3, 3))))


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
    clearance: Clearance | None = None,
) -> tuple[np.ndarray, float]:
    """Move `joints` in `data.qpos` so `site` reaches the target; return (qpos, error).

    Position error is in metres; with a target rotation, the orientation error (rad) is
    added with weight 0.1 m/rad. Joint limits are enforced every iteration. `clearance`
    keeps geom pairs apart (the error counts only the site's pose).
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
        apart = [] if clearance is None else clearance.rows(model, data, dadr)
        if err < tol and not apart:
            break
        if apart:
            e = np.concatenate([e, *(r for r, _ in apart)])
            jac += [jr for _, jr in apart]
        j = np.vstack(jac)
        dq = j.T @ np.linalg.solve(j @ j.T + damping * np.eye(j.shape[0]), e)
        data.qpos[qadr] = np.clip(data.qpos[qadr] + dq, lo, hi)
    return data.qpos[qadr].copy(), err


@dataclass(frozen=True)
class Clearance:
    """Geom pairs (moving geom, obstacle geom) the IK keeps `margin` metres apart.

    A pair closer than that adds one row: the moving geom's nearest point, pushed along
    the pair's separating direction by the shortfall (weight 1, like the site's
    position, so the pose gives way where both cannot hold). An obstacle the joints
    move too (an arm's own hand) counts with its nearest point's motion taken off.
    """

    pairs: tuple[tuple[int, int], ...]
    margin: float = 0.01

    def rows(self, model: mujoco.MjModel, data: mujoco.MjData, dadr: np.ndarray
             ) -> list[tuple[np.ndarray, np.ndarray]]:
        """(error, jacobian) rows of the pairs within the margin now."""
        out = []
        fromto = np.zeros(6)
        jacp = np.zeros((3, model.nv))
        for geom, obstacle in self.pairs:
            dist = mujoco.mj_geomDistance(model, data, geom, obstacle, self.margin, fromto)
            if dist >= self.margin:
                continue
            away = fromto[:3] - fromto[3:]
            norm = np.linalg.norm(away)
            if norm < 1e-9:
                continue
            away *= np.sign(dist) / norm if dist else 1.0 / norm
            mujoco.mj_jac(model, data, jacp, None, fromto[:3], model.geom_bodyid[geom])
            row = away @ jacp[:, dadr]
            if model.body_weldid[model.geom_bodyid[obstacle]]:  # the obstacle moves too
                mujoco.mj_jac(model, data, jacp, None, fromto[3:], model.geom_bodyid[obstacle])
                row = row - away @ jacp[:, dadr]
            out.append((np.array([self.margin - dist]), row[None]))
        return out


def multi_turn(model: mujoco.MjModel, joints: list[str]) -> np.ndarray:
    """(len(joints),) whether each joint is a hinge turning more than a full turn
    (unlimited, or its range spans more than 2 pi): there `q` and `q +- 2 pi` are the
    same pose, and a warm-started IK keeps whichever it began near, not the one the arm
    can turn to."""
    jids = [model.joint(j).id for j in joints]
    span = model.jnt_range[jids, 1] - model.jnt_range[jids, 0]
    hinge = model.jnt_type[jids] == mujoco.mjtJoint.mjJNT_HINGE
    return hinge & (~model.jnt_limited[jids].astype(bool) | (span > 2 * np.pi + 1e-6))


def path_blocked(model: mujoco.MjModel, data: mujoco.MjData, qadr: np.ndarray,
                 start: np.ndarray, end: np.ndarray, pairs: tuple[tuple[int, int], ...],
                 step: float = 0.1) -> bool:
    """Whether the straight joint path from `start` to `end` (`qpos[qadr]`, the rest of
    `data.qpos` as it is) drives a geom pair into each other on its way: past touching
    and deeper than at either end, so an arm already pressed against its own hand may
    move apart, and a pose the IK puts just into it (the same at every turn of a joint)
    counts against no path. Checked every `step` rad of the largest joint's travel, each
    pair only where their bounding spheres overlap."""
    geoms = np.array(pairs, dtype=int).reshape(-1, 2)
    reach = model.geom_rbound[geoms].sum(axis=1)
    fromto = np.zeros(6)
    samples = max(1, int(np.ceil(np.abs(end - start).max() / step)))

    def depths(k: int) -> np.ndarray:
        """Each pair's penetration (negative distance) at sample `k`, 0 where apart."""
        data.qpos[qadr] = start + (end - start) * k / samples
        mujoco.mj_kinematics(model, data)
        apart = np.linalg.norm(data.geom_xpos[geoms[:, 0]] - data.geom_xpos[geoms[:, 1]], axis=1)
        out = np.zeros(len(geoms))
        for p in np.flatnonzero(apart < reach):
            out[p] = mujoco.mj_geomDistance(model, data, *geoms[p], 0.0, fromto)
        return out

    ends = np.minimum(depths(0), depths(samples))
    return any((depths(k) < ends - 1e-3).any() for k in range(1, samples))


def _rotation_error(current: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Axis-angle vector (world frame) rotating `current` onto `target`."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (target @ current.T).ravel())
    vel = np.zeros(3)
    mujoco.mju_quat2Vel(vel, quat, 1.0)
    return vel
