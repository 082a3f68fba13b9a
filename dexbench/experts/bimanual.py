"""Two-hand lift: each hand hooks one grip point of an object, both lift it together.

For trays and similar wide objects held at two opposite rims (BimanualLiftTray). Each
hand comes down palm-down on its grip point with the fingers pointing at the object's
centre, curls its fingers over and inside the rim, then pulls outward so the curled
fingers press the rim: the two pulls balance, and friction carries the object. A closed
box (BimanualLiftCarton, `press`) has no rim: each open palm comes in from the side onto
the middle of a side face and pushes on into it, and the two pushes squeeze the box. Both
palms then rise by the same height, which keeps the object level. When the object slips
(a grip point leaves its hand, or it tilts), both hands open, back off and try again.

Poses are relative to the object's functional points and each hand's `grasp_offset`; the
left hand's frame is mirrored (its thumb is on the other side of the hand frame's y
axis), which the script measures from the fingertips instead of assuming.
"""

from __future__ import annotations

from enum import IntEnum

import mujoco
import numpy as np
import torch

from dexbench.embodiments.hand_geometry import actuated_joints, palm_face
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import ActionAdapter, HandCommand, nearly_best, site_pose
from dexbench.experts.base import host_ids
from dexbench.experts.motion import palm_down, step_towards, turned, way_poses
from dexbench.tasks.plans import TwoHandPlan
from dexbench.tasks.predicates import tilt_deg


class Phase(IntEnum):
    APPROACH = 0  # both hands above their grip poses, open
    DESCEND = 1  # down onto the grip poses
    CLOSE = 2  # curl the fingers over the rims
    PULL = 3  # pull outward: the curled fingers press the rims
    LIFT = 4  # both palms rise by the same height
    RELEASE = 5  # a lost grip: open, back off, start again


APPROACH_HEIGHT = 0.08  # m behind (above) the palm of the grip pose
SPEED = 0.5  # m/s palm speed limit in free space
CAREFUL_SPEED = 0.2  # m/s descending and pulling
LIFT_SPEED = 0.12  # m/s: slow enough that the fingers keep their hold
TURN_RATE = 3.0  # rad/s
NEAR = 0.01  # m: command this close to the pose above the grip counts as there
ARRIVED = 0.008  # m: actual palms this close to the grip poses start the closing
PAUSE_SECONDS = 0.2
CLOSE_SECONDS = 0.6
SETTLE_SECONDS = 0.3
PULL_SECONDS = 0.4
LOST_DISTANCE = 0.04  # m a grip point may move in its hand before the grip counts as lost
LOST_TILT = 8.0  # deg: the task fails at 10, so regrasp before
OPEN_SECONDS = 0.4


FLOOR_GAP = 0.015  # m: a pressing hand's longest fingertip above the object's base
# rad a pressing hand may turn about its palm normal (fingers off vertical, the face on
# its point): an arm whose wrist cannot hang the fingers straight down beside the box
# (the UR10e's and xArm7's with the Shadow hand) takes the least turn it reaches as well
# as any (`ActionAdapter.reach_cost` within `REACH_MARGIN` of the best). Up to 0.6 rad
# the xArm7 with Wuji or Allegro hands turned for a nearer pose and lost a box it held
# unturned (1.00 -> 0.10, 0.00); up to 0.4 they keep it (8 and 6 of 8).
ROLLS = (0.0, -0.2, 0.2, -0.4, 0.4)
WAYPOINTS = 4  # poses from the hand's to above its grip that `_choose_rolls` scores too
HOOK_INSIDE = 0.02  # m: a hooking hand's closed fingertips past the grip point (a rim's
# middle): half the rim's thickness, a fingertip's radius and some play


def facing(yaw: np.ndarray) -> np.ndarray:
    """(N, 3, 3) hand frames with the palm facing world yaw `yaw` (N,), horizontally, and
    the fingers pointing down: the forearm, thicker than the palm, stays above a box a
    level hand would touch with it."""
    z = np.column_stack([np.cos(yaw), np.sin(yaw), np.zeros(len(yaw))])
    x = np.broadcast_to([0.0, 0.0, -1.0], z.shape)
    return np.stack([x, np.cross(z, x), z], axis=2)


def _rolled(frames: np.ndarray, roll: float | np.ndarray) -> np.ndarray:
    """(N, 3, 3) hand frames turned by `roll` (rad) about their own palm normals."""
    return turned(frames[:, :, 2], roll) @ frames


class TwoHandLiftExpert:
    """The two-hand hook-and-lift phase machine; both hands of an env share one phase."""

    def __init__(self, env: DexEnv, plan: TwoHandPlan) -> None:
        self.env, self.plan = env, plan
        self.adapter = ActionAdapter(env)
        info = env.task.objects[plan.obj]
        self.body = info.root
        self._points = {side: info.points[name] for side, name in plan.grips.items()}
        self._up = info.axes["up"]
        model = env.scene.model
        layouts = env.embodiment.sides
        self._palm_site = {s: model.site(layouts[s].palm_site).id for s in plan.grips}
        self._thumb_site = {s: model.site(layouts[s].fingertip_sites[0]).id for s in plan.grips}
        self._tip_sites = {s: [model.site(t).id for t in layouts[s].fingertip_sites]
                           for s in plan.grips}
        self._rest = info.rest_height
        self._offset = np.asarray(env.embodiment.hand.grasp_offset) + plan.shift
        self._dt = env.control_dt
        n = env.num_envs
        self.phase = np.zeros(n, dtype=np.int64)
        self.timer = np.zeros(n)
        self.closure = np.zeros(n)
        self.height = np.zeros(n)  # how far both palms have risen since the pull
        eye = np.repeat(np.eye(3)[None], n, axis=0)
        self.pos = {s: np.zeros((n, 3)) for s in plan.grips}
        self.rot = {s: eye.copy() for s in plan.grips}
        self.grip_pos = {s: np.zeros((n, 3)) for s in plan.grips}
        self.grip_rot = {s: eye.copy() for s in plan.grips}
        self.held = {s: np.zeros((n, 3)) for s in plan.grips}
        self.offset = {s: self._offset.copy() for s in plan.grips}
        self.full = dict.fromkeys(plan.grips, 1.0)  # a closed hand's closure: see `_hook`
        self.roll = {s: np.zeros(n) for s in plan.grips}  # rad about the palm normal
        self._arm = env.embodiment.mount != "floating"
        self._hooks: dict[str, tuple[float, np.ndarray]] = {}  # per side, from the first reset

    def _palm(self, side: str) -> tuple[np.ndarray, np.ndarray]:
        return site_pose(self.env, self._palm_site[side])

    def _mirror(self, env: int) -> dict[str, float]:
        """-1 for a side whose thumb lies across the hand frame's y axis from the right
        hand's (a mirrored frame): its grasp offset's y flips. Read in a just-reset
        env `env`, whose hands are open."""
        thumb_y = {}
        for side in self.plan.grips:
            pos, rot = self._palm(side)
            thumb = self.env.sim.field("site_xpos")[:, self._thumb_site[side]].cpu().numpy()
            thumb_y[side] = (rot[env].T @ (thumb[env] - pos[env]))[1]
        ref = thumb_y.get("right", next(iter(thumb_y.values())))
        return {s: 1.0 if y * ref >= 0 else -1.0 for s, y in thumb_y.items()}

    def _press_offset(self, side: str, env: int) -> np.ndarray:
        """Where a pressing hand's grip point lies in the hand frame: below the palm
        (along the fingers) for the open hand's furthest reach to end `FLOOR_GAP` above
        the object's base; across the hand at the middle of its pressing face
        (`palm_face`), since two palms bearing off the object's middle let it swing about
        their line as they lift; and the plan's `shift` out from that face, so every
        hand's face ends equally deep in the object however far its palm stands out of
        its palm site. Read in a just-reset env `env`."""
        view = self.env.view
        point = view.point_pos(*self._points[side])[env, 2]
        base = view.body_pos(self.body)[env, 2] - self._rest
        face = palm_face(self.env.embodiment.hand.name, side)
        return np.array([face.reach + FLOOR_GAP - (point - base), face.centre[1],
                         face.height + self.plan.shift[2]])

    def _hook(self, side: str, env: int) -> tuple[float, np.ndarray]:
        """The closure at which the fingertips (thumb aside) reach deepest below the palm,
        a hook: fingers that curl on back under the palm (the Allegro's) would lift off
        the rim again. And where the grip point lies in the hand frame for those tips to
        end `HOOK_INSIDE` past it along the fingers, level with it and centred across them.
        Kinematics of the joints between `open` and `power` on env `env`'s state, in a
        scratch copy: the hands are open when this is needed."""
        model, emb = self.env.scene.model, self.env.embodiment
        data = mujoco.MjData(model)
        data.qpos[:] = self.env.sim.field("qpos")[env].cpu().numpy()
        opened, closed = self.adapter.pose("open"), self.adapter.pose("power")
        joints = []  # (action index, qpos addresses, their share of the target)
        for i in emb.hand_actuators(side):
            act = model.actuator(emb.actuators[i])
            driven = actuated_joints(model, act.id)  # coupled joints share a tendon's
            if driven:
                joints.append((i, [model.jnt_qposadr[j] for j, _ in driven],
                               1.0 / (act.gear[0] * sum(c for _, c in driven))))
        palm, tip_sites = self._palm_site[side], self._tip_sites[side][1:]
        best = (-np.inf, 1.0, np.zeros(3))
        for closure in np.linspace(0.0, 1.0, 21):
            for i, adr, share in joints:
                data.qpos[adr] = (opened[i] + closure * (closed[i] - opened[i])) * share
            mujoco.mj_kinematics(model, data)
            rot = data.site_xmat[palm].reshape(3, 3)
            tips = ((data.site_xpos[tip_sites] - data.site_xpos[palm]) @ rot).mean(axis=0)
            if tips[2] > best[0] + 1e-4:
                best = (tips[2], closure, tips)
        return float(best[1]), best[2] - [HOOK_INSIDE, 0.0, 0.0]

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        for side, mirror in self._mirror(int(ids[0])).items():
            if self.plan.press:
                self.offset[side] = self._press_offset(side, int(ids[0]))
            elif self.plan.hook:  # the hand's own geometry: the same at every reset
                if side not in self._hooks:
                    self._hooks[side] = self._hook(side, int(ids[0]))
                self.full[side], grip = self._hooks[side]
                self.offset[side] = grip + np.multiply(self.plan.shift, [1.0, mirror, 1.0])
            else:
                self.offset[side] = self._offset * [1.0, mirror, 1.0]
            pos, rot = self._palm(side)
            self.pos[side][ids], self.rot[side][ids] = pos[ids], rot[ids]
            self.roll[side][ids] = 0.0
        if self.plan.press and self._arm:
            self._choose_rolls(ids)
        self.phase[ids], self.timer[ids], self.closure[ids] = Phase.APPROACH, 0.0, 0.0
        self.adapter.reset(ids)

    def _choose_rolls(self, ids: np.ndarray) -> None:
        """Per side and env, the least of `ROLLS` whose press (the way in from the hand's
        pose to above the grip pose, on it, pushed in) the arm reaches about as well as
        with any of them. Without the way in, a turn whose grip pose the scratch IK found
        from the arm's joints in one go left the UR10e's left arm, following its way there
        step by step, 21 cm and 31 deg off the grip (BimanualLiftCarton x
        bimanual_ur10e_shadow 0.45 -> 0.90 with it). The lift is left
        out: an arm that reaches the press but not the lift's top (the UR10e with Allegro
        hands) lifts the box past the task's height anyway, and turned for the top it
        lost the box (1.00 -> 0.05)."""
        poses = self._grip_poses()
        for side, (point, rot) in poses.items():
            for i in ids:
                costs = []
                for roll in ROLLS:
                    frame = _rolled(rot[i][None], roll)[0]
                    grip = point[i] - frame @ self.offset[side]
                    above = grip - APPROACH_HEIGHT * frame[:, 2]
                    path = [*way_poses(self.pos[side][i], self.rot[side][i], above, frame,
                                       WAYPOINTS), (grip, frame),
                            (grip + self.plan.pull * frame[:, 2], frame)]
                    costs.append(self.adapter.reach_cost(side, int(i), path))
                self.roll[side][i] = ROLLS[nearly_best(costs)]

    def _grip_poses(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Per side: the grip point (world) and the hand frame there: palm-down, fingers
        pointing from it at the object's centre, or (`press`) palm facing the centre,
        fingers down."""
        view = self.env.view
        centre = view.body_pos(self.body).cpu().numpy()
        poses = {}
        for side, (body, local) in self._points.items():
            point = view.point_pos(body, local).cpu().numpy()
            inward = centre - point
            yaw = np.arctan2(inward[:, 1], inward[:, 0])
            poses[side] = point, (_rolled(facing(yaw), self.roll[side]) if self.plan.press
                                  else palm_down(yaw))
        return poses

    def act(self) -> torch.Tensor:
        self.timer += self._dt
        phase, sides = self.phase, list(self.plan.grips)
        poses = self._grip_poses()
        # Follow the object until the fingers close.
        tracking = (phase == Phase.APPROACH) | (phase == Phase.DESCEND)
        for side, (point, rot) in poses.items():
            self.grip_rot[side][tracking] = rot[tracking]
            self.grip_pos[side][tracking] = (point - rot @ self.offset[side])[tracking]
        target_pos = {s: self.grip_pos[s].copy() for s in sides}
        target_rot = {s: self.grip_rot[s].copy() for s in sides}
        palms = {s: self._palm(s) for s in sides}

        approach = phase == Phase.APPROACH
        near = approach.copy()
        for s in sides:
            above = self.grip_pos[s] - APPROACH_HEIGHT * self.grip_rot[s][:, :, 2]
            target_pos[s][approach] = above[approach]
            near &= np.linalg.norm(self.pos[s] - above, axis=1) < NEAR
        self._advance((near & (self.timer > 0.3)) | (approach & (self.timer > 3.0)),
                      Phase.DESCEND)

        descend = phase == Phase.DESCEND
        arrived = descend.copy()
        for s in sides:
            arrived &= ((np.linalg.norm(self.pos[s] - self.grip_pos[s], axis=1) < 0.005)
                        & (np.linalg.norm(palms[s][0] - self.grip_pos[s], axis=1) < ARRIVED))
        self._advance(arrived | (descend & (self.timer > 2.5)), Phase.CLOSE)

        close = phase == Phase.CLOSE
        closing = np.clip((self.timer - PAUSE_SECONDS) / CLOSE_SECONDS, 0.0, 1.0)
        self.closure[close] = 0.0 if self.plan.press else closing[close]
        self._advance(close & (self.timer > PAUSE_SECONDS + CLOSE_SECONDS + SETTLE_SECONDS),
                      Phase.PULL)

        pull = phase == Phase.PULL
        for s in sides:
            way = self.grip_rot[s][:, :, 2] if self.plan.press else -self.grip_rot[s][:, :, 0]
            target_pos[s][pull] = (self.grip_pos[s] + self.plan.pull * way)[pull]
        pulled = pull & (self.timer > PULL_SECONDS)
        for s in sides:
            # Where the closed hand holds its grip point, in the hand frame.
            point, (palm, palm_rot) = poses[s][0], palms[s]
            self.held[s][pulled] = np.einsum("nji,nj->ni", palm_rot, point - palm)[pulled]
            self.grip_pos[s][pulled] = self.pos[s][pulled]  # the lift starts from here
        self.height[pulled] = 0.0
        self._advance(pulled, Phase.LIFT)

        lift = phase == Phase.LIFT
        if lift.any():
            self.height[lift] = np.minimum(self.height[lift] + LIFT_SPEED * self._dt,
                                           self.plan.lift)
            lost = lift & (tilt_deg(self.env.view.axis(*self._up)).cpu().numpy() > LOST_TILT)
            for s in sides:
                target_pos[s][lift] = self.grip_pos[s][lift] + self.height[lift, None] * [
                    0.0, 0.0, 1.0]
                point, (palm, palm_rot) = poses[s][0], palms[s]
                expected = palm + np.einsum("nij,nj->ni", palm_rot, self.held[s])
                lost |= lift & (np.linalg.norm(point - expected, axis=1) > LOST_DISTANCE)
            self._advance(lost, Phase.RELEASE)

        release = phase == Phase.RELEASE
        # Open in place first, then back off upwards.
        self.closure[release] = np.maximum(0.0, 1.0 - self.timer[release] / OPEN_SECONDS)
        rising = (self.timer > OPEN_SECONDS)[release, None]
        for s in sides:
            target_pos[s][release] = self.pos[s][release] + [0.0, 0.0, 0.05] * rising
            target_rot[s][release] = self.rot[s][release]
        self._advance(release & (self.timer > 2 * OPEN_SECONDS), Phase.APPROACH)

        careful = (phase == Phase.DESCEND) | (phase == Phase.PULL) | (phase == Phase.LIFT)
        speed = np.where(careful, CAREFUL_SPEED, SPEED)[:, None] * self._dt
        commands = {}
        for s in sides:
            self.pos[s], self.rot[s] = step_towards(self.pos[s], self.rot[s], target_pos[s],
                                                    target_rot[s], speed, TURN_RATE * self._dt)
            commands[s] = HandCommand(self.pos[s], self.rot[s], self.full[s] * self.closure)
        return self.adapter.actions(commands)

    def _advance(self, mask: np.ndarray, phase: Phase) -> None:
        self.phase[mask] = phase
        self.timer[mask] = 0.0
