"""Push a ball along a path with one fingertip, steering it back onto the path.

For balls pushed up a ramp between obstacles (PushSmallSphereObstacleSlope). The hand
hangs edge-on over the path and points its index finger, the other fingers curled
(the hand's `pinch` there, `open` on the index and thumb): a thin pusher that fits
between posts, nothing else near the slope. The index leans forward, its tip ahead of
its knuckle, and its lowest point (measured on the hand) skims just above the ball's
bottom, so it pushes the ball from low behind: higher, the push presses the ball into
the slope and bends the finger's weak joints back. A ball moves along the line from the
contact through its centre, so every step the fingertip is put behind the ball on the
line to a point a little further along the path and pressed on (the fingertip: where the
finger's front meets the ball, measured on its geoms); the line starts from
where the ball will be shortly (steering on where it is overshoots and weaves). The
push starts only once the fingertip itself has caught up with its command behind the
ball: an arm trails the fast descent by ~3 cm, as far as a fingertip stuck on a post
trails its push, and a push begun that early read as stuck at once, over and over. The
fingertip's steady offset from its command across the push (an arm's, ~5 mm) is taken
out of the command: it turns the line, and the ball weaves off it onto a post. When
the fingertip has lost the ball (it rolled aside) or is stuck, the hand goes back
behind it from above; once `done`, the hand rises.
"""

from __future__ import annotations

from enum import IntEnum

import mujoco
import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import (
    ActionAdapter,
    HandCommand,
    palm_and_finger_sites,
    tips_in_palm_frame,
)
from dexbench.experts.base import host_ids
from dexbench.experts.motion import step_towards
from dexbench.experts.push import TIP_RADIUS, PushExpert
from dexbench.experts.surface import FingerEnds, front_aim
from dexbench.tasks.plans import PathPushPlan


class Phase(IntEnum):
    ABOVE = 0  # over the point behind the ball
    DOWN = 1  # down behind the ball
    PUSH = 2  # pushing, steering
    DONE = 3  # lifted off


SPEED = 0.4  # m/s in the air
PUSH_SPEED = 0.06  # m/s of the fingertip while pushing
TURN_RATE = 3.0  # rad/s
PRESS = 0.015  # m the command leads the fingertip into the ball
# m along the path: where the ball is steered towards. Near, so a ball that veered off
# (a finger's abduction gives under the push) turns back onto the line before the posts:
# at 0.1 the Inspire hand's balls ran onto a post (all four mounts 9 of 40 -> 28 of 40
# over episodes 10-19 at 0.05; Shadow, Sharpa, Allegro unchanged but UR10e Allegro 10 -> 8).
LOOKAHEAD = 0.05
PREDICT = 0.4  # s: the ball is steered from where it will be this much later
HIGH = 0.08  # m above the ball's top: the finger's lowest point travelling over it
# m: the finger's lowest point (its geoms' extreme points) above the ball's bottom while
# pushing. At 4 mm the Wuji hand solved none of 20 episodes on any mount; at the ~9 mm its
# geoms' bounding boxes gave it before, 0.25-0.30 floating and on the FR3; at 6, 0.90-1.00.
CLEAR = 0.006
STANDOFF = 0.02  # m between fingertip and ball before pushing
ARRIVED = 0.006  # m
LOST = 0.045  # m: the fingertip this far from the ball's back has lost it ...
PASSED = 0.01  # m: ... as when it is this far ahead of the ball's centre
BLOCKED = 0.03  # m the fingertip trails its command: stuck (on a post, a rail): go round
# m: the push starts only once the fingertip itself trails its command by less: an arm
# trails the fast descent by ~3 cm (a floating wrist by ~1.5), which would read as blocked
SETTLED = 0.01
LEAN = 0.45  # rad the pointing finger leans forward from vertical
BAND = 0.006  # m above and below the ball's centre height: the finger's front is sought there
POINT = "point"  # the adapter pose: index and thumb open, the other fingers curled


def along(path: np.ndarray, point: np.ndarray, ahead: float) -> np.ndarray:
    """(N, 3) the point `ahead` m further along polylines `path` (N, K, 3) than the
    nearest point to `point` (N, 3) (clamped to the path's end), in the horizontal."""
    a, b = path[:, :-1], path[:, 1:]
    seg = b - a
    length = np.linalg.norm(seg[..., :2], axis=-1)
    t = ((point[:, None, :2] - a[..., :2]) * seg[..., :2]).sum(-1) / np.maximum(length, 1e-9) ** 2
    t = np.clip(t, 0.0, 1.0)
    near = a + t[..., None] * seg
    k = np.linalg.norm(near[..., :2] - point[:, None, :2], axis=-1).argmin(axis=1)
    rows = np.arange(len(path))
    cum = np.concatenate([np.zeros((len(path), 1)), np.cumsum(length, axis=1)], axis=1)
    s = cum[rows, k] + t[rows, k] * length[rows, k] + ahead
    s = np.minimum(s, cum[:, -1])
    j = np.clip((cum[:, 1:] < s[:, None]).sum(axis=1), 0, seg.shape[1] - 1)
    u = (s - cum[rows, j]) / np.maximum(length[rows, j], 1e-9)
    return a[rows, j] + u[:, None] * seg[rows, j]


class PathPushExpert:
    """The ball pusher for the right hand of a single-hand env."""

    def __init__(self, env: DexEnv, plan: PathPushPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self._palm, self._tips = palm_and_finger_sites(env, side)
        self.adapter.add_pose(POINT, pointing_pose(env, side))
        info = env.task.objects[plan.obj]
        self.body, self.radius = info.root, info.rest_height
        n = env.num_envs
        self.phase = np.zeros(n, dtype=np.int64)
        self.offsets = np.zeros((n, len(self._tips), 3))
        self.pos = np.zeros((n, 3))  # commanded leading fingertip
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.hang = self.rot.copy()  # the pushing hand frame
        self.lead = np.zeros(n, dtype=np.int64)  # the index: first of the non-thumb tips
        self.last = np.zeros((n, 3))  # the ball's position a control step ago
        self.reach = np.zeros(n)  # m the hanging index reaches below its fingertip site
        self._ends = FingerEnds(env, self._palm, self._tips[:1])

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        palm, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.offsets[ids] = tips[ids]
        path = np.asarray(self.plan.path(self.env))
        d = path[:, -1] - path[:, 0]
        d[:, 2] = 0.0
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        ends = self._ends()
        below = ends - self.offsets[:, :1]  # the finger's surface about its tip site
        for i in ids:
            self.hang[i], self.lead[i] = self._pusher(i, d[i])
            self.reach[i] = -(below[i] @ self.hang[i].T)[:, 2].min()
            self.offsets[i, 0] = self._aim(i, d[i], ends[i])
        self.rot[ids] = rot[ids]
        self.pos[ids] = palm[ids] + np.einsum("nij,nj->ni", rot[ids],
                                              self.offsets[ids, self.lead[ids]])
        self.phase[ids] = Phase.ABOVE
        self.last[ids] = self.env.view.body_pos(self.body).cpu().numpy()[ids].copy()
        self.adapter.reset(ids)

    def _pusher(self, i: int, d: np.ndarray) -> tuple[np.ndarray, int]:
        """The hanging hand frame whose fingertip row lies along push `d` (3,), the index
        leading and leaning forward by `LEAN`, and the index's fingertip number (0)."""
        best = None
        for turn in (0.0, np.pi):
            for tilt in (LEAN, -LEAN):
                yaw = np.arctan2(d[1], d[0]) - self._row_yaw() + turn
                rot = PushExpert._hanging(np.array([yaw]), np.array([tilt]))[0]
                tips = self.offsets[i] @ rot.T
                ahead = tips[0] @ d + 10.0 * ((tips @ d).argmax() == 0)
                if best is None or ahead > best[0]:
                    best = (ahead, rot)
        return best[1], 0

    def _aim(self, i: int, d: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """The pointing finger's point the pusher steers (hand frame; `surface.front_aim`):
        its front (its geoms' extreme points `ends`, hand frame) where it meets the ball's
        centre height. Steering the tip site, 3 cm behind and 1.6 cm to the side of LEAP's
        front, pushed the ball off its line (floating LEAP 1 of 10 episodes, 10 of 10 so)."""
        site, points = self.hang[i] @ self.offsets[i, 0], ends @ self.hang[i].T
        centre = site[2] + self.radius - self.reach[i] - CLEAR
        level = np.abs(points[:, 2] - centre) < BAND
        return front_aim(site, points, level, d, TIP_RADIUS) @ self.hang[i]

    @staticmethod
    def _row_yaw() -> float:
        hanging = PushExpert._hanging(np.zeros(1), np.zeros(1))[0]
        return float(np.arctan2(hanging[1, 1], hanging[0, 1]))

    def act(self) -> torch.Tensor:
        ball = self.env.view.body_pos(self.body).cpu().numpy()
        # Steer where the ball is going: steering on where it is overshoots the line.
        ahead = ball + PREDICT * (ball - self.last) / self.env.control_dt
        self.last = ball.copy()
        path = np.asarray(self.plan.path(self.env))
        d = along(path, ahead, LOOKAHEAD) - ahead
        d[:, 2] = 0.0
        d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)
        back = self.radius + TIP_RADIUS
        behind = ball - d * (back + STANDOFF)
        behind[:, 2] += self.reach + CLEAR - self.radius
        rows = np.arange(len(ball))
        palm, rot, _ = tips_in_palm_frame(self.env, self._palm, self._tips)
        tip = palm + np.einsum("nij,nj->ni", rot, self.offsets[rows, self.lead])
        rel = ball - tip
        rel[:, 2] = 0.0
        gap = np.linalg.norm(rel, axis=1)
        passed = (rel * d).sum(1) < -PASSED
        done = np.asarray(self.plan.done(self.env), dtype=bool)
        phase = self.phase
        lag = np.linalg.norm(self.pos - tip, axis=1)
        blocked = lag > BLOCKED
        phase[(phase == Phase.PUSH) & ((gap > back + LOST) | passed | blocked)] = Phase.ABOVE
        phase[done] = Phase.DONE
        phase[(phase == Phase.DONE) & ~done] = Phase.ABOVE
        target = behind.copy()
        above = phase == Phase.ABOVE
        target[above, 2] = (ball[:, 2] + self.radius + self.reach + HIGH)[above]
        push = phase == Phase.PUSH
        # The fingertip's offset from its command across the push turns the ball's line.
        drift = tip - self.pos
        drift[:, 2] = 0.0
        drift -= (drift * d).sum(1, keepdims=True) * d
        target[push] = (behind + (STANDOFF + PRESS) * d - drift)[push]
        fin = phase == Phase.DONE
        target[fin] = self.pos[fin] + [0.0, 0.0, HIGH]
        target[fin, 2] = np.minimum(target[fin, 2], ball[fin, 2] + HIGH)
        speed = np.where(push, PUSH_SPEED, SPEED)[:, None] * self.env.control_dt
        self.pos, self.rot = step_towards(self.pos, self.rot, target, self.hang, speed,
                                          TURN_RATE * self.env.control_dt)
        arrived = np.linalg.norm(self.pos - target, axis=1) < ARRIVED
        phase[above & arrived] = Phase.DOWN
        phase[(phase == Phase.DOWN) & arrived & (lag < SETTLED) & ~above] = Phase.PUSH
        palm_cmd = self.pos - np.einsum("nij,nj->ni", self.rot, self.offsets[rows, self.lead])
        closure = np.ones(len(ball))
        return self.adapter.actions({self.side: HandCommand(palm_cmd, self.rot, closure, POINT)})


def pointing_pose(env: DexEnv, side: str) -> np.ndarray:
    """Every actuator's target: the hand's `pinch`, but `open` on the index and thumb
    (the actuators moving a joint between the hand's root and their fingertips)."""
    model, emb = env.scene.model, env.embodiment
    sites = emb.sides[side].fingertip_sites[:2]
    chains = set()
    for site in sites:
        body = model.site(site).bodyid[0]
        while body > 0:
            chains.add(int(body))
            body = model.body_parentid[body]
    pose = emb.poses["pinch"].copy()
    for a in emb.hand_actuators(side):
        if chains & _moved_bodies(model, a):
            pose[a] = emb.poses["open"][a]
    return pose


def _moved_bodies(model: mujoco.MjModel, actuator: int) -> set[int]:
    """Bodies whose joints an actuator drives (directly or through a joint tendon)."""
    target = model.actuator_trnid[actuator, 0]
    if model.actuator_trntype[actuator] == mujoco.mjtTrn.mjTRN_JOINT:
        return {int(model.jnt_bodyid[target])}
    adr, num = model.tendon_adr[target], model.tendon_num[target]
    return {int(model.jnt_bodyid[model.wrap_objid[w]]) for w in range(adr, adr + num)
            if model.wrap_type[w] == mujoco.mjtWrap.mjWRAP_JOINT}
