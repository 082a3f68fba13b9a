"""Tip pinch: pick a thin object lying on the table between the thumb and index tips.

A thin object (a pen) lying on the table is lower than any power grasp's fingers can
reach, and the other fingers sweep it away. Here the hand comes down with the thumb and
index tips already part-closed on either side of it, across its axis, so that they
close the last few centimetres under its middle, sliding on the table, while the other
fingers stay clear above. Where the two tips meet, and the line they close along, are
measured once per hand from its model (`pinch_geometry`), so the script serves any hand
whose synergy brings those tips together.
"""

from __future__ import annotations

import functools
from enum import IntEnum

import mujoco
import numpy as np
import torch

from dexbench.embodiments.hand_geometry import hand_geometry, hand_model_spec
from dexbench.embodiments.hands import HANDS
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import ActionAdapter, HandCommand, site_pose
from dexbench.experts.base import host_ids, phase_machine_state
from dexbench.experts.grasp import squeezed
from dexbench.experts.motion import palm_down, step_towards, turned, wrap
from dexbench.tasks.plans import PinchPlan, locate


class Phase(IntEnum):
    APPROACH = 0  # above the grasp pose, fingers preshaped
    DESCEND = 1  # straight down onto it
    CLOSE = 2  # close the tips under the object, then let them settle
    LIFT = 3  # rise and hold
    RELEASE = 4  # open and back off (a lost object), then grasp again


APPROACH_HEIGHT = 0.08  # m above the grasp pose
SPEED = 0.4  # m/s in free space
CAREFUL_SPEED = 0.15  # m/s descending and lifting
TURN_RATE = 3.0  # rad/s
ARRIVED = 0.006  # m: the actual palm this close to the grasp pose starts the closing
CLOSE_SECONDS = 1.5
LOST_DISTANCE = 0.04  # m the held point may move from where the hand closed on it
OPEN_SECONDS = 0.4
BACK_OFF = 0.06  # m
PATH_POINTS = 8  # closures at which `pinch_path` measures the tips


def _settled(model: mujoco.MjModel, data: mujoco.MjData, ctrl: np.ndarray) -> None:
    """Drive the free-floating hand model to `ctrl` from rest until it stops (<= 4 s)."""
    mujoco.mj_resetData(model, data)
    data.ctrl[:] = ctrl
    for step in range(2000):
        mujoco.mj_step(model, data)
        if step > 100 and np.abs(data.qvel).max() < 1e-4:
            break


def _nearest(model: mujoco.MjModel, data: mujoco.MjData, a: list[int], b: list[int],
             ) -> tuple[np.ndarray, np.ndarray]:
    """The nearest points of two sets of geoms (a's, b's)."""
    best, points, fromto = np.inf, (np.zeros(3), np.zeros(3)), np.zeros(6)
    for ga in a:
        for gb in b:
            dist = mujoco.mj_geomDistance(model, data, ga, gb, 1.0, fromto)
            if dist < best:
                best, points = dist, (fromto[:3].copy(), fromto[3:].copy())
    return points


@functools.cache
def pinch_path(hand_name: str, side: str, synergy: str, preshape: float,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How the thumb and index tips close, at closures (K,) from `preshape` to 1 towards
    `synergy`: the midpoints of their nearest points (K, 3) and the lowest point of each
    (K, 2, 3; palm-down, the first to touch the table), in the hand frame
    (`HandSpec.grasp_offset`). Measured on the hand alone, gravity-free (the mounted hand
    is gravity-compensated), the lowest points against a plane 1 m below the palm."""
    hand = HANDS[hand_name]
    geo = hand_geometry(hand_name, side)
    site_rot = np.zeros(9)
    mujoco.mju_quat2Mat(site_rot, geo.palm_site_quat)
    spec = hand_model_spec(hand, side)
    floor_rot = geo.frame_rot @ np.diag([1.0, -1.0, -1.0])  # z: towards the palm
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, floor_rot.ravel())
    spec.worldbody.add_geom(name="pinch_floor", type=mujoco.mjtGeom.mjGEOM_PLANE,
                            size=[1.0, 1.0, 0.01], contype=0, conaffinity=0,
                            pos=(geo.frame_pos + geo.frame_rot[:, 2]).tolist(),
                            quat=quat.tolist())
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.timestep = 0.002
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    model = spec.compile()
    data = mujoco.MjData(model)
    parts = hand.sides[side]
    palm = model.body(parts.palm_body).id

    def geoms(body: str) -> list[int]:
        bid = model.body(body).id
        return [g for g in range(model.ngeom) if model.geom_bodyid[g] == bid
                and (model.geom_contype[g] or model.geom_conaffinity[g])]

    tips = [geoms(body) for body in parts.fingertip_bodies[:2]]
    floor, fromto = model.geom("pinch_floor").id, np.zeros(6)
    opened, closed = geo.synergies["open"], geo.synergies[synergy]
    closures = np.linspace(preshape, 1.0, PATH_POINTS)
    mids, lows = [], []
    for closure in closures:
        _settled(model, data, opened + closure * (closed - opened))
        rot = data.xmat[palm].reshape(3, 3) @ site_rot.reshape(3, 3)

        def local(point: np.ndarray, rot: np.ndarray = rot) -> np.ndarray:
            return rot.T @ (point - data.xpos[palm])

        mids.append(sum(local(p) for p in _nearest(model, data, *tips)) / 2)
        low = []
        for tip in tips:
            dists = [mujoco.mj_geomDistance(model, data, floor, g, 2.0, fromto) for g in tip]
            mujoco.mj_geomDistance(model, data, floor, tip[int(np.argmin(dists))], 2.0, fromto)
            low.append(local(fromto[3:].copy()))
        lows.append(low)
    return closures, np.array(mids), np.array(lows)


def width_closure(closures: np.ndarray, lows: np.ndarray, width: float) -> float:
    """The closure at which the tips' lowest points `lows` (K, 2, 3) first stand `width`
    apart across the hand (where they meet an object that wide; the nearest if never)."""
    apart = np.linalg.norm((lows[:, 1] - lows[:, 0])[:, :2], axis=1)
    inside = np.flatnonzero(apart <= width)
    if inside.size == 0 or inside[0] == 0:
        return float(closures[np.abs(apart - width).argmin()])
    k = inside[0]
    return float(np.interp(width, apart[[k, k - 1]], closures[[k, k - 1]]))


def level_tilt(lows: np.ndarray) -> np.ndarray:
    """(3, 3) roll of the hand frame about its x axis (along the fingers: the wrist and
    forearm stay up) that puts the two tips' lowest points `lows` (2, 3) level when the
    hand is palm-down."""
    d = lows[1] - lows[0]
    return turned(np.array([[1.0, 0.0, 0.0]]), np.arctan(-d[2] / d[1]))[0]


class PinchExpert:
    """The tip-pinch phase machine for one hand of a single-hand env."""

    def __init__(self, env: DexEnv, plan: PinchPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self.pose = squeezed(self.adapter, env, plan.synergy, plan.squeeze)
        self.closures, mids, lows = pinch_path(env.embodiment.hand.name, side,
                                               plan.synergy, plan.preshape)
        # The hand tilts so the tips come down level (as far closed as `level`), and its
        # yaw puts the line between them (palm down) across the object's axis. In the
        # level frame: where the tips are (x, y: between them; z: the lower one) as the
        # fingers close.
        level = plan.preshape if plan.level is None else plan.level
        if plan.width is not None:
            level = width_closure(self.closures, lows, plan.width)
        self.tilt = level_tilt(lows[np.abs(self.closures - level).argmin()])
        mids, lows = mids @ self.tilt.T, lows @ self.tilt.T
        self.tips = np.column_stack([mids[:, :2], lows[:, :, 2].max(axis=1)])
        self.tips = self.tips + np.asarray(plan.shift)
        self.below = np.array([0.0, 0.0, plan.depth])
        across = palm_down(np.zeros(1))[0] @ (lows[0, 1] - lows[0, 0])
        self.line_yaw = float(np.arctan2(across[1], across[0]))
        info = env.task.objects[plan.obj]
        self.body, self.point = locate(env.task.objects, plan.obj, plan.point)
        self.goal_body, self.goal_local = (
            (self.body, self.point) if plan.goal_point is None
            else locate(env.task.objects, plan.obj, plan.goal_point))
        self.axis = info.axes[plan.axis]
        self._palm = env.scene.model.site(env.embodiment.sides[side].palm_site).id
        self._dt = env.control_dt
        n = env.num_envs
        self.phase, self.timer, self.closure, self.pos, self.rot = phase_machine_state(n)
        self.pinch_at = np.zeros((n, 3))
        self.grasp_rot = self.rot.copy()
        self.held = np.zeros((n, 3))
        self.lift_to = np.zeros((n, 3))
        self.held_goal = np.zeros((n, 3))  # the goal point in the palm frame, once closed
        self.carry = np.zeros(n, dtype=bool)  # risen, carrying it to the plan's target

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        self.pos[ids], self.rot[ids] = (v[ids] for v in site_pose(self.env, self._palm))
        self.phase[ids], self.timer[ids], self.closure[ids] = Phase.APPROACH, 0.0, 0.0
        self.carry[ids] = False
        self.adapter.reset(ids)

    def _grasp_rot(self, current: np.ndarray) -> np.ndarray:
        """(N, 3, 3) palm-down frames with the tips' line across the object's axis, of the
        two the one nearest the hand's current yaw, or, for an object that hangs from a
        hand that holds it so (`HandSpec.hang_back`), the one whose fingers point away
        from the object's longer part (from the pinched point to its body's origin)."""
        axis = self.env.view.axis(*self.axis).cpu().numpy()
        yaw = np.arctan2(axis[:, 1], axis[:, 0]) + np.pi / 2 - self.line_yaw
        if self.plan.hangs and self.env.embodiment.hand.hang_back:
            view = self.env.view
            longer = (view.body_pos(self.body) - view.point_pos(self.body, self.point)
                      ).cpu().numpy()
            out = longer[:, 0] * np.cos(yaw) + longer[:, 1] * np.sin(yaw) > 0.0
            return palm_down(wrap(yaw + np.pi * out))
        now = np.arctan2(current[:, 1, 0], current[:, 0, 0])
        return palm_down(wrap(now + (yaw - now + np.pi / 2) % np.pi - np.pi / 2))

    def act(self) -> torch.Tensor:
        view = self.env.view
        point = view.point_pos(self.body, self.point).cpu().numpy()
        self.timer += self._dt
        phase = self.phase
        palm, palm_rot = site_pose(self.env, self._palm)
        fresh = (phase == Phase.APPROACH) & (self.timer <= self._dt)
        if fresh.any():
            self.grasp_rot[fresh] = self._grasp_rot(self.rot)[fresh]
        tracking = (phase == Phase.APPROACH) | (phase == Phase.DESCEND)
        self.pinch_at[tracking] = (point - self.below)[tracking]
        # The palm goes where the tips, as far closed as commanded, meet at `pinch_at`: the
        # hand moves with their closing so they sweep in level, towards the object.
        tips = np.stack([np.interp(self.closure, self.closures, self.tips[:, k])
                         for k in range(3)], axis=1)
        self.grasp_pos = self.pinch_at - np.einsum("nij,nj->ni", self.grasp_rot, tips)
        target_pos, target_rot = self.grasp_pos.copy(), self.grasp_rot @ self.tilt
        above = self.grasp_pos + np.array([0.0, 0.0, APPROACH_HEIGHT])
        approach = phase == Phase.APPROACH
        # Rise first when low (a hand that just let go), then across, then down.
        low = approach & (self.pos[:, 2] < above[:, 2] - 0.01) & (
            np.linalg.norm((self.pos - above)[:, :2], axis=1) > 0.02)
        target_pos[approach] = above[approach]
        target_pos[low] = np.column_stack([self.pos[:, :2], above[:, 2]])[low]
        target_rot[low] = self.rot[low]
        self.closure[tracking] = self.plan.preshape
        near = np.linalg.norm(self.pos - above, axis=1) < 0.005
        self._advance(approach & ((near & (self.timer > 0.3)) | (self.timer > 3.0)),
                      Phase.DESCEND)

        descend = phase == Phase.DESCEND
        arrived = ((np.linalg.norm(self.pos - self.grasp_pos, axis=1) < 0.003)
                   & (np.linalg.norm(palm - self.grasp_pos, axis=1) < ARRIVED))
        self._advance(descend & (arrived | (self.timer > 2.0)), Phase.CLOSE)

        close = phase == Phase.CLOSE
        pre, full = self.plan.preshape, self.plan.squeeze
        self.closure[close] = (pre + (full - pre) * np.minimum(self.timer / CLOSE_SECONDS, 1.0)
                               )[close]
        target_pos[close] = self.grasp_pos[close]
        done = close & (self.timer > CLOSE_SECONDS + self.plan.settle)
        self.held[done] = np.einsum("nji,nj->ni", palm_rot, point - palm)[done]
        self.lift_to[done] = (self.pos + np.array([0.0, 0.0, self.plan.lift]))[done]
        goal_now = view.point_pos(self.goal_body, self.goal_local).cpu().numpy()
        self.held_goal[done] = np.einsum("nji,nj->ni", palm_rot, goal_now - palm)[done]
        self.carry[done] = False
        self._advance(done, Phase.LIFT)

        lift = phase == Phase.LIFT
        if self.plan.target is not None:  # risen: on to where the goal point meets the target
            self.carry |= lift & (np.linalg.norm(self.pos - self.lift_to, axis=1) < 1e-3)
            carry_to = (self.plan.target(self.env)
                        - np.einsum("nij,nj->ni", self.rot, self.held_goal))
            self.lift_to[self.carry] = carry_to[self.carry]
        target_pos[lift] = self.lift_to[lift]
        expected = palm + np.einsum("nij,nj->ni", palm_rot, self.held)
        self._advance(lift & (np.linalg.norm(point - expected, axis=1) > LOST_DISTANCE),
                      Phase.RELEASE)

        release = phase == Phase.RELEASE
        self.closure[release] = np.maximum(0.0, 1.0 - self.timer / OPEN_SECONDS)[release]
        back_off = self.pos - BACK_OFF * self.rot[:, :, 2]
        rising = self.timer > OPEN_SECONDS
        target_pos[release] = np.where(rising[:, None], back_off, self.pos)[release]
        target_rot[release] = self.rot[release]
        self._advance(release & (self.timer > 2 * OPEN_SECONDS), Phase.APPROACH)

        careful = (phase == Phase.DESCEND) | (phase == Phase.LIFT)
        speed = np.where(careful, CAREFUL_SPEED, SPEED)[:, None] * self._dt
        self.pos, self.rot = step_towards(self.pos, self.rot, target_pos, target_rot,
                                          speed, TURN_RATE * self._dt)
        command = HandCommand(self.pos, self.rot, self.closure / self.plan.squeeze, self.pose)
        return self.adapter.actions({self.side: command})

    @property
    def carrying(self) -> np.ndarray:
        """(N,) holding the object (lifting it, or lifted)."""
        return self.phase == Phase.LIFT

    @property
    def finished(self) -> np.ndarray:
        """(N,) lifted: the hand holds the object where it rose to."""
        return (self.phase == Phase.LIFT) & (
            np.linalg.norm(self.pos - self.lift_to, axis=1) < 1e-3)

    def _advance(self, mask: np.ndarray, phase: Phase) -> None:
        self.phase[mask] = phase
        self.timer[mask] = 0.0
