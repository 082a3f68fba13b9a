"""Grasp-and-move: approach from above, close a synergy, then lift or carry to a goal.

One closed-loop script for the tasks whose core is "hold one object and move it"
(PickCube, PickUpStick, RelocateSphere, RelocateObject, StackCube, ...). Each env runs
its own phase machine; when the object slips out of the hand the env opens, backs off
and grasps again. Poses are relative to the object (its grasp point and symmetry) and
the hand's `grasp_offset`, so the script serves every hand and mount.
"""

from __future__ import annotations

from enum import IntEnum

import mujoco
import numpy as np
import torch

from dexbench.embodiments.hand_geometry import hand_geometry
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.rotations import quat_apply
from dexbench.experts.adapter import ActionAdapter, HandCommand, site_pose, subtree
from dexbench.experts.base import host_ids, phase_machine_state
from dexbench.experts.motion import (
    HANDSHAKE_ROT,
    TRAVEL_RISE,
    body_yaw,
    box_yaw,
    palm_down,
    pitch_down,
    step_towards,
    via_travel,
    yawed,
)
from dexbench.tasks.plans import GraspPlan, LevelPlan, locate
from dexbench.tasks.predicates import tilt_deg


class Phase(IntEnum):
    APPROACH = 0  # above the grasp pose, hand open
    DESCEND = 1  # down onto the grasp pose
    CLOSE = 2  # close the synergy in place
    CARRY = 3  # move the held object where the task wants it
    RELEASE = 4  # open and back off (a lost grasp, or a placed object)
    DONE = 5  # placed: stay clear, hand open


APPROACH_HEIGHT = 0.10  # m behind the palm of the grasp pose
APPROACH_LIFT = 0.03  # m, side grasps also come in from slightly above
SPEED = 0.45  # m/s palm speed limit in free space
CAREFUL_SPEED = 0.2  # m/s descending onto the object and carrying it
TURN_RATE = 3.0  # rad/s
ARRIVED = 0.008  # m: the actual palm this close to the grasp pose starts the closing
PAUSE_SECONDS = 0.2  # still, open, at the grasp pose before closing
CLOSE_SECONDS = 0.5
SETTLE_SECONDS = 1.0  # closed and still before moving: lets weak fingers seat the object
LOST_DISTANCE = 0.05  # held point this far from where the hand closed on it: retry
PLACE_TOLERANCE = 0.006  # m: a placed object is let go within this of its target
OPEN_SECONDS = 0.4
CARRY_HEIGHT = 0.12  # m above the grasp: carrying height while far from the target
CARRY_NEAR = 0.02  # m: horizontally this close to the target, the object goes down


def squeezed(adapter: ActionAdapter, env: DexEnv, synergy: str, factor: float) -> str:
    """The name of a pose closing `factor` times as far as `synergy` from `open` (clipped
    to the actuators' ranges), added to `adapter`: position-controlled fingers told to go
    further press harder on what stops them."""
    if factor == 1.0:
        return synergy
    opened, closed = adapter.pose("open"), adapter.pose(synergy)
    ranges = env.embodiment.ctrl_range
    name = f"{synergy}_x{factor:g}"
    adapter.add_pose(name, np.clip(opened + factor * (closed - opened),
                                   ranges[:, 0], ranges[:, 1]))
    return name


def stand_off(expert: GraspExpert, distance: float, reach: float = 0.04) -> float:
    """How far (m) `expert`'s grasp pose must move back along the palm normal (negative:
    in) for the open hand there to stand `distance` clear of the object (negative: pressed
    into it): the hand's own size, not the plan's, then sets how close its palm comes, so
    a thick palm or an open thumb standing off the palm does not push the object over on
    its way in, and a handle rests in the fingers' hook alike for every hand. Measured
    once, between the open hand (its settled `open` joints) and the object placed at the
    grasp in a scratch copy of the scene, at most `reach` either way (2 mm steps);
    objects not free to move give 0."""
    env, side = expert.env, expert.side
    info = env.task.objects[expert.plan.obj]
    if info.free_joint is None:
        return 0.0
    model = env.scene.model
    data = mujoco.MjData(model)
    layout = env.embodiment.sides[side]
    prefix = layout.hand_root.removesuffix(env.embodiment.hand.sides[side].palm_body)
    for joint, q in hand_geometry(env.embodiment.hand.name, side).open_qpos.items():
        if prefix + joint in layout.hand_joints:
            data.qpos[model.joint(prefix + joint).qposadr[0]] = q
    mujoco.mj_kinematics(model, data)
    palm = model.site(layout.palm_site).id
    palm_pos, palm_rot = data.site_xpos[palm].copy(), data.site_xmat[palm].reshape(3, 3).copy()
    # The grasp planned on the object upright at the origin, into slot 0 (every slot is
    # planned afresh on its first approach).
    body = model.body(expert.body).id
    free = model.joint(info.free_joint).qposadr[0]
    data.qpos[free:free + 7] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    mujoco.mj_kinematics(model, data)
    point = data.xpos[body] + data.xmat[body].reshape(3, 3) @ np.asarray(expert.point)
    n = env.num_envs
    expert._plan_grasp(np.array([0]), np.repeat(point[None], n, axis=0),
                       np.repeat(data.xquat[body][None], n, axis=0))
    grasp_pos, grasp_rot = expert.grasp_pos[0], expert.grasp_rot[0]
    colliding = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    held = subtree(model, model.body(info.root).id)
    hand = [g for g in env.scene.hand_geoms
            if model.body(model.geom_bodyid[g]).name.startswith(f"{side}/hand/")]
    pairs = [(a, b) for a in hand
             for b in np.flatnonzero(colliding & np.isin(model.geom_bodyid, list(held)))]
    # Move the object, not the hand: the palm stays at home, the object goes where the
    # grasp pose (moved back by `back`) puts it relative to the palm.
    turn = palm_rot @ grasp_rot.T
    mujoco.mju_mat2Quat(data.qpos[free + 3:free + 7], turn.ravel())
    fromto = np.zeros(6)
    for back in np.arange(-reach, reach, 0.002):
        data.qpos[free:free + 3] = palm_pos - turn @ (grasp_pos - back * grasp_rot[:, 2])
        mujoco.mj_kinematics(model, data)
        gap = min(mujoco.mj_geomDistance(model, data, a, b, distance + 0.01, fromto)
                  for a, b in pairs)
        if gap >= distance:
            return float(back)
    return 0.0


class GraspExpert:
    """The grasp-and-move phase machine for the right hand of a single-hand env."""

    def __init__(self, env: DexEnv, plan: GraspPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env, commanded_hand=plan.commanded_hand)
        self.synergy = squeezed(self.adapter, env, plan.synergy, plan.squeeze)
        hand = env.embodiment.hand
        self.offset = (np.asarray(hand.grasp_offset) + np.asarray(plan.shift)
                       + np.asarray(hand.shift_for(plan.hand_shift)))
        objects = env.task.objects
        self.body, self.point = locate(objects, plan.obj, plan.point)
        self.goal_body, self.goal_point = locate(objects, plan.obj, plan.goal_point)
        model = env.scene.model
        self._palm_site = model.site(env.embodiment.sides[side].palm_site).id
        self._dt = env.control_dt
        n = env.num_envs
        self.phase, self.timer, self.closure, self.pos, self.rot = phase_machine_state(n)
        self.grasp_pos = np.zeros((n, 3))
        self.grasp_rot = self.rot.copy()
        self.lift_from = np.zeros((n, 3))
        self.placed = np.zeros(n, dtype=bool)
        self.held = np.zeros((n, 3))
        self.travel_z = np.zeros(n)
        if plan.standoff is not None:
            self.offset[2] += stand_off(self, plan.standoff)

    def _palm(self) -> tuple[np.ndarray, np.ndarray]:
        return site_pose(self.env, self._palm_site)

    def object_point(self, body: str, local: tuple[float, float, float],
                     ) -> tuple[np.ndarray, np.ndarray]:
        view = self.env.view
        pos = view.body_pos(body)
        quat = view.body_quat(body)
        offset = torch.as_tensor(local, dtype=pos.dtype, device=pos.device).expand(pos.shape)
        return (pos + quat_apply(quat, offset)).cpu().numpy(), quat.cpu().numpy()

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot = self._palm()
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.phase[ids], self.timer[ids], self.closure[ids] = Phase.APPROACH, 0.0, 0.0
        self.placed[ids] = False
        self.adapter.reset(ids)

    def _plan_grasp(self, ids: np.ndarray, point: np.ndarray, quat: np.ndarray) -> None:
        yaw = {"box": box_yaw, "body": body_yaw,
               "none": lambda q: np.zeros(len(q))}[self.plan.yaw](quat[ids])
        offset = self.plan.yaw_offset
        yaw = yaw + (offset(self.env)[ids] if callable(offset) else offset)
        rot = yawed(HANDSHAKE_ROT, yaw) if self.plan.side else palm_down(yaw)
        rot = rot @ pitch_down(self.plan.pitch)
        self.grasp_rot[ids] = rot
        self.grasp_pos[ids] = point[ids] - rot @ self.offset

    def act(self) -> torch.Tensor:
        point, quat = self.object_point(self.body, self.point)
        self.timer += self._dt
        phase = self.phase
        target_pos, target_rot = self.grasp_pos.copy(), self.grasp_rot.copy()

        if self.plan.wait is not None:  # not setting out yet: planned afresh once it does
            self.timer[(phase == Phase.APPROACH) & ~np.asarray(self.plan.wait(self.env))] = 0.0
        fresh = (phase == Phase.APPROACH) & (self.timer <= self._dt)
        if fresh.any():
            self._plan_grasp(np.flatnonzero(fresh), point, quat)
        # Follow the object until the fingers close (its yaw is kept from the plan).
        tracking = (phase == Phase.APPROACH) | (phase == Phase.DESCEND)
        self.grasp_pos[tracking] = (point - self.grasp_rot @ self.offset)[tracking]
        target_pos[tracking] = self.grasp_pos[tracking]
        approach = phase == Phase.APPROACH
        # Approach from behind the palm: above for top grasps, from the side for side ones.
        above = self.grasp_pos - APPROACH_HEIGHT * self.grasp_rot[:, :, 2]
        above[:, 2] += APPROACH_LIFT * self.plan.side
        # Travel at a height clear of what the hand just held, rising (without turning)
        # before moving across, so it sweeps nothing over: a hand leaving a drawer
        # handle would otherwise push the drawer shut.
        self.travel_z[fresh] = np.maximum(above[:, 2], self.pos[:, 2] + TRAVEL_RISE)[fresh]
        waypoint, low = via_travel(self.pos, above, self.travel_z)
        target_pos[approach] = waypoint[approach]
        target_rot[approach & low] = self.rot[approach & low]
        waiting = approach & (self.timer == 0.0)
        target_pos[waiting], target_rot[waiting] = self.pos[waiting], self.rot[waiting]
        near = np.linalg.norm(self.pos - above, axis=1) < 0.01
        self._advance(approach & ((near & (self.timer > 0.3)) | (self.timer > 3.0)),
                      Phase.DESCEND)

        descend = phase == Phase.DESCEND
        # Close once the hand itself is there: an arm may trail its command.
        palm, _ = self._palm()
        arrived = ((np.linalg.norm(self.pos - self.grasp_pos, axis=1) < 0.005)
                   & (np.linalg.norm(palm - self.grasp_pos, axis=1)
                      < (ARRIVED if self.plan.arrive is None else self.plan.arrive)))
        self._advance(descend & (arrived | (self.timer > 2.5)), Phase.CLOSE)

        close = phase == Phase.CLOSE
        closing = np.clip((self.timer - PAUSE_SECONDS) / CLOSE_SECONDS, 0.0, 1.0)
        self.closure[close] = closing[close]
        settle = SETTLE_SECONDS if self.plan.settle is None else self.plan.settle
        done = close & (self.timer > PAUSE_SECONDS + CLOSE_SECONDS + settle)
        self.lift_from[done] = self.pos[done]
        # Where the closed hand actually holds the object, in the hand frame.
        palm, palm_rot = self._palm()  # the actual hand: an arm may lag its command
        self.held[done] = np.einsum("nji,nj->ni", palm_rot, point - palm)[done]
        self._advance(done, Phase.CARRY)

        carry = phase == Phase.CARRY
        if carry.any():
            expected = palm + np.einsum("nij,nj->ni", palm_rot, self.held)
            lost = carry & (np.linalg.norm(point - expected, axis=1) > LOST_DISTANCE)
            if self.plan.target is None:
                target_pos[carry] = (self.lift_from + np.array([0.0, 0.0, self.plan.lift]))[carry]
            else:
                goal_point, _ = self.object_point(self.goal_body, self.goal_point)
                # A copy: `task_goal` may be a view of the task's own goal, which the
                # raise below must not move (the success check and the goal observation
                # read it).
                goal = np.array(self.plan.target(self.env), dtype=float)
                # Travel above the table's clutter; come down only over the target.
                far = np.linalg.norm((goal - goal_point)[:, :2], axis=1) > CARRY_NEAR
                far &= self.plan.carry_high
                goal[:, 2] = np.where(far, np.maximum(goal[:, 2], goal_point[:, 2]
                                                      + (self.lift_from[:, 2] + CARRY_HEIGHT
                                                         - self.pos[:, 2])), goal[:, 2])
                error = goal - goal_point
                target_pos[carry] = (self.pos + error)[carry]
                if self.plan.release:
                    placed = carry & (np.linalg.norm(error, axis=1) < PLACE_TOLERANCE)
                    self.placed |= placed
                    lost |= placed
            if self.plan.let_go is not None:
                done = carry & self.plan.let_go(self.env)
                self.placed |= done
                lost |= done
            self._advance(lost, Phase.RELEASE)

        release = phase == Phase.RELEASE
        # Open in place first, then back off: rising while open drags the object along.
        self.closure[release] = np.maximum(0.0, 1.0 - self.timer[release] / OPEN_SECONDS)
        # Backing off is away from the palm side: up for a top grasp, back for a hook.
        rising = self.timer > OPEN_SECONDS
        back_off = self.pos - self.plan.back_off * self.rot[:, :, 2]
        target_pos[release] = np.where(rising[:, None], back_off, self.pos)[release]
        target_rot[release] = self.rot[release]
        released = release & (self.timer > 2 * OPEN_SECONDS)
        self._advance(released & ~self.placed, Phase.APPROACH)
        self._advance(released & self.placed, Phase.DONE)
        done = phase == Phase.DONE
        target_pos[done], target_rot[done] = self.pos[done], self.rot[done]

        careful = (phase == Phase.DESCEND) | (phase == Phase.CARRY)
        slow = CAREFUL_SPEED if self.plan.carry_speed is None else self.plan.carry_speed
        speed = np.where(careful, slow, SPEED)[:, None] * self._dt
        self.pos, self.rot = step_towards(self.pos, self.rot, target_pos, target_rot,
                                          speed, TURN_RATE * self._dt)
        command = HandCommand(self.pos, self.rot, self.closure, self.synergy)
        return self.adapter.actions({self.side: command})

    @property
    def carrying(self) -> np.ndarray:
        """(N,) holding the object and moving it."""
        return self.phase == Phase.CARRY

    @property
    def finished(self) -> np.ndarray:
        """(N,) the object has been placed (or let go) and the hand is clear."""
        return self.phase == Phase.DONE

    def _advance(self, mask: np.ndarray, phase: Phase) -> None:
        self.phase[mask] = phase
        self.timer[mask] = 0.0


class LevelGraspExpert(GraspExpert):
    """A `LevelPlan`: the grasp whose carry also pitches the hand fingers-down as far as
    keeps the held object at the plan's tilt (an object held by one end sags)."""

    def __init__(self, env: DexEnv, plan: LevelPlan, side: str = "right") -> None:
        super().__init__(env, plan.grasp, side)
        self.level = plan
        self._axis = env.task.objects[plan.grasp.obj].axes[plan.axis]
        self.angle = np.zeros(env.num_envs)
        self.base = self.grasp_rot.copy()

    def act(self) -> torch.Tensor:
        plan = self.level
        carry = self.phase == Phase.CARRY
        start = carry & (self.angle == 0.0)
        self.base[start] = self.grasp_rot[start]
        tilt = tilt_deg(self.env.view.axis(*self._axis)).cpu().numpy()
        sag = np.where(plan.active(self.env), plan.tilt - tilt, 0.0)
        step = plan.rate * self._dt * np.clip(sag / 10.0, -1.0, 1.0)
        self.angle = np.where(carry, np.clip(self.angle + step, 0.0, plan.max_angle), 0.0)
        for i in np.flatnonzero(carry):
            self.grasp_rot[i] = self.base[i] @ pitch_down(self.angle[i])
        return super().act()
