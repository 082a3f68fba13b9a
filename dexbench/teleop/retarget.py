"""Human hand keypoints -> joint targets of any embodiment, by IK on its MuJoCo model.

Input per hand side: a `HandFrame`, 21 keypoints in MediaPipe/MANO order (0 wrist, thumb
1-4, index 5-8, middle 9-12, ring 13-16, pinky 17-20; metres, world frame) and the wrist
pose (4x4, world frame). The wrist frame has the axes of our hand frame H: x from the
wrist towards the middle knuckle, z the palm normal (out of the palm, the way the fingers
curl), y = z x x (towards the little finger on a right hand, the thumb on a left one);
its origin is keypoint 0. "World" is the scene's world frame: a source registers its
operator space to the scene before frames get here.

Fingers: `mink` (differential IK on the compiled MuJoCo model: joint limits, tendons and
the real kinematics, no URDF) places each fingertip site, relative to the palm site, where
the hand spec's `RetargetSpec` maps the human fingertip; a posture task keeps the rest
near the open hand. Mount: the palm site goes to the wrist pose through the damped
least-squares IK the experts use (`solve_site_pose`), for floating and arm mounts alike.
Output: one absolute target per actuator, in the embodiment's action order.
"""

from __future__ import annotations

from dataclasses import dataclass

import mink
import mujoco
import numpy as np

from dexbench.assets.objects import new_spec
from dexbench.embodiments.builder import add_embodiment
from dexbench.embodiments.hands import RetargetSpec
from dexbench.embodiments.ik import solve_site_pose
from dexbench.embodiments.layout import Embodiment

NUM_KEYPOINTS = 21
FINGER_ITERATIONS = 30  # mink steps per frame; a warm start needs few
MOUNT_ITERATIONS = 50
POSTURE_COST = 1e-3  # per rad, against 1 per m of the fingertip tasks: a tie-breaker
TOLERANCE = 1e-4  # m, fingertip error at which a frame's finger IK stops early
HUMAN_PALM = 0.095  # m, a human's wrist to middle knuckle (`RetargetSpec`)
MIDDLE = 2  # the middle finger's place among the fingertip bodies (thumb, index, middle)


@dataclass(frozen=True)
class HandFrame:
    """One hand at one instant: `keypoints` (21, 3) and `wrist` (4, 4), world frame."""

    keypoints: np.ndarray
    wrist: np.ndarray

    def local(self) -> np.ndarray:
        """(21, 3) keypoint offsets from the wrist keypoint, in the wrist frame."""
        return (self.keypoints - self.keypoints[0]) @ self.wrist[:3, :3]


def wrist_pose(keypoints: np.ndarray, side: str) -> np.ndarray:
    """(4, 4) wrist pose of a hand from its 21 keypoints alone (for sources that give no
    wrist rotation, such as MediaPipe): x to the middle knuckle (9), y along the knuckle
    line (index 5 to pinky 17 on a right hand, the reverse on a left), z = x x y."""
    x = keypoints[9] - keypoints[0]
    x /= np.linalg.norm(x)
    across = keypoints[17] - keypoints[5]
    y = across if side == "right" else -across
    y = y - y.dot(x) * x
    y /= np.linalg.norm(y)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, y, np.cross(x, y)])
    pose[:3, 3] = keypoints[0]
    return pose


def robot_as_human(palm_pos: np.ndarray, palm_rot: np.ndarray, tips: np.ndarray,
                   wrist_point: np.ndarray, spec: RetargetSpec) -> HandFrame:
    """A robot hand's pose as the keypoints of a human hand `spec.scale` times smaller:
    the wrist keypoint at the hand's wrist point (`Retargeter.wrist`, palm site frame),
    the fingertip keypoints `spec.tips` at the fingertip sites `tips` (n, 3, world) pulled
    towards it, the other keypoints on the wrist-tip lines; the wrist frame is the palm's.
    Robot motion recorded this way drives another hand as a human's would."""
    wrist = palm_pos + palm_rot @ wrist_point
    human_tips = wrist + (tips - wrist) / spec.scale
    keypoints = np.repeat(wrist[None], NUM_KEYPOINTS, axis=0)
    for finger in range(5):
        tip = human_tips[min(finger, len(human_tips) - 1)]
        for k in range(4):
            keypoints[1 + 4 * finger + k] = wrist + (k + 1) / 4 * (tip - wrist)
    keypoints[list(spec.tips)] = human_tips
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = palm_rot, wrist
    return HandFrame(keypoints, pose)


class Retargeter:
    """Joint targets for embodiment `name` from human hand frames, one call per instant.

    Works on a robot-only model of the embodiment, whose actuators are the env's
    (`env.embodiment.actuators`, same order). Each call warm-starts from the last one.
    """

    def __init__(self, name: str) -> None:
        spec = new_spec()
        plan = add_embodiment(spec, name)
        self.model = spec.compile()
        self.embodiment = Embodiment.resolve(plan, self.model)
        self.data = mujoco.MjData(self.model)
        self.configuration = mink.Configuration(self.model)
        # First warm start, as dex-retargeting's: finger joints at mid-range (a half-bent
        # finger flexes the right way; from straight, a tip target can pull a joint onto
        # its limit), everything else at home.
        self._start = np.zeros(self.model.nq)
        for joint, q in self.embodiment.home_qpos.items():
            self._start[self.model.joint(joint).qposadr[0]] = q
        for layout in self.embodiment.sides.values():
            palm = self.model.site(layout.palm_site).bodyid[0]
            for j in range(self.model.njnt):
                if self.model.jnt_limited[j] and _below(self.model, self.model.jnt_bodyid[j],
                                                        palm):
                    self._start[self.model.jnt_qposadr[j]] = self.model.jnt_range[j].mean()
        self.reset()
        self.wrist = {side: self._wrist_point(side) for side in self.embodiment.sides}
        # The fingertip tasks are relative to the palm, so the mount does not enter them;
        # with no posture cost either, its velocity is zero and its warm start stays.
        mount = [self.model.joint(j).dofadr[0] for s in self.embodiment.sides.values()
                 for j in s.mount_joints]
        cost = np.full(self.model.nv, POSTURE_COST)
        cost[mount] = 0.0
        self.posture = mink.PostureTask(self.model, cost=cost)
        self.limits = [mink.ConfigurationLimit(self.model)]
        self.tasks: dict[str, list[mink.RelativeFrameTask]] = {}
        for side, layout in self.embodiment.sides.items():
            tips = self.embodiment.hand.retarget.tips
            if len(tips) != len(layout.fingertip_sites):
                raise ValueError(f"{name}: RetargetSpec.tips maps {len(tips)} fingers, "
                                 f"the hand has {len(layout.fingertip_sites)}")
            self.tasks[side] = [
                mink.RelativeFrameTask(site, "site", layout.palm_site, "site",
                                       position_cost=1.0, orientation_cost=0.0)
                for site in layout.fingertip_sites]

    @property
    def actuators(self) -> tuple[str, ...]:
        """The action layout of the returned targets."""
        return self.embodiment.actuators

    def reset(self) -> None:
        """Back to the first warm start (mount at home, fingers at mid-range)."""
        self.configuration.update(self._start.copy())

    def _wrist_point(self, side: str) -> np.ndarray:
        """Where the human wrist keypoint sits on this hand, in the palm site frame: `scale`
        x `HUMAN_PALM` behind the middle finger's first joint, along the fingers (derived
        per side: the left and right models need not be mirror images)."""
        model, data = self.model, self.configuration.data
        layout = self.embodiment.sides[side]
        palm_site = model.site(layout.palm_site).id
        palm = model.site_bodyid[palm_site]
        chain = [model.body(layout.fingertip_bodies[MIDDLE]).id]
        while model.body_parentid[chain[-1]] != palm:
            chain.append(model.body_parentid[chain[-1]])
        knuckle = next(j for body in reversed(chain) for j in range(model.njnt)
                       if model.jnt_bodyid[j] == body)
        rot = data.site_xmat[palm_site].reshape(3, 3)
        anchor = (data.xanchor[knuckle] - data.site_xpos[palm_site]) @ rot
        return anchor - np.array([self.embodiment.hand.retarget.scale * HUMAN_PALM, 0, 0])

    def tip_targets(self, frame: HandFrame, side: str = "right") -> np.ndarray:
        """(n_tips, 3) where the mapped fingertip sites should be, in the palm site frame."""
        spec = self.embodiment.hand.retarget
        return self.wrist[side] + spec.scale * frame.local()[list(spec.tips)]

    def palm_target(self, frame: HandFrame, side: str = "right",
                    ) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation of the palm site that put the hand's wrist point on
        the human wrist keypoint, axes aligned with the wrist frame."""
        rot = frame.wrist[:3, :3]
        return frame.keypoints[0] - rot @ self.wrist[side], rot

    def retarget(self, frames: dict[str, HandFrame]) -> np.ndarray:
        """(nu,) actuator targets realising `frames` (one per side; a side without a frame
        keeps its last solution), clipped to the control ranges."""
        for side, frame in frames.items():
            self._solve_fingers(side, frame)
        q = self.configuration.q.copy()
        self.data.qpos[:] = q
        for side, frame in frames.items():
            layout = self.embodiment.sides[side]
            pos, rot = self.palm_target(frame, side)
            solve_site_pose(self.model, self.data, layout.palm_site, list(layout.mount_joints),
                            pos, rot, iterations=MOUNT_ITERATIONS)
        self.configuration.update(self.data.qpos.copy())
        mujoco.mj_fwdPosition(self.model, self.data)
        # A position actuator drives its length (joint angle, or tendon length for the
        # Shadow hand's coupled J1+J2) towards ctrl: the solved length is the target.
        ctrl = self.data.actuator_length.copy()
        return np.clip(ctrl, self.embodiment.ctrl_range[:, 0], self.embodiment.ctrl_range[:, 1])

    def _solve_fingers(self, side: str, frame: HandFrame) -> None:
        tasks = self.tasks[side]
        for task, target in zip(tasks, self.tip_targets(frame, side), strict=True):
            task.set_target(mink.SE3.from_translation(target))
        # Ties go to the last frame's solution: smooth motion (dex-retargeting's norm_delta).
        self.posture.set_target(self.configuration.q)
        for _ in range(FINGER_ITERATIONS):
            vel = mink.solve_ik(self.configuration, [*tasks, self.posture], dt=1.0,
                                solver="daqp", damping=1e-6, limits=self.limits)
            self.configuration.integrate_inplace(vel, 1.0)
            err = max(np.linalg.norm(t.compute_error(self.configuration)[:3]) for t in tasks)
            if err < TOLERANCE:
                break

    def fingertip_error(self, frames: dict[str, HandFrame]) -> dict[str, np.ndarray]:
        """Per side, (n_tips,) distance (m) between each fingertip site of the current
        solution and its target, both in the palm site frame."""
        data = self.configuration.data
        out = {}
        for side, frame in frames.items():
            layout = self.embodiment.sides[side]
            palm = self.model.site(layout.palm_site).id
            pos, rot = data.site_xpos[palm], data.site_xmat[palm].reshape(3, 3)
            tips = np.array([data.site_xpos[self.model.site(s).id]
                             for s in layout.fingertip_sites])
            out[side] = np.linalg.norm((tips - pos) @ rot - self.tip_targets(frame, side),
                                       axis=1)
        return out


def _below(model: mujoco.MjModel, body: int, ancestor: int) -> bool:
    """Whether `body` is `ancestor` or in its subtree."""
    while body != ancestor and body != 0:
        body = model.body_parentid[body]
    return body == ancestor
