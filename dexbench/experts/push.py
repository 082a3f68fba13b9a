"""Push a flat block to a planar goal pose with one fingertip, re-planning every push.

For blocks too flat to grasp (PushT): the hand hangs its fingers down, turned so the
row of fingertips lies along the push and the outermost fingertip leads, a point pusher
just above the table. Each push is chosen greedily: over contact points on the block's
outline (inward pushes) and push lengths, a quasi-static model (the block turns about its
centroid by the push's moment over its radius of gyration squared) predicts the pose
after the push; the push that most reduces the pose error per second (travel included)
wins. The hand goes there over the block when the straight way would touch it, pushes,
and plans again. Fingertips are measured on the hand itself, so the script serves every
hand and mount: the push steers the leading finger's front (its geoms' extreme points at
the block's side), not its tip site, which lies 2 cm behind it on the LEAP hand, and
judges the push's progress by that point carried with the palm.
"""

from __future__ import annotations

import numpy as np
import torch

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.embodiments.ik import rotation_angle
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import (
    REACH_MARGIN,
    ActionAdapter,
    HandCommand,
    palm_and_finger_sites,
    site_pose,
    tips_in_palm_frame,
)
from dexbench.experts.base import host_ids
from dexbench.experts.motion import body_yaw, palm_down, pitch_down, step_towards, wrap
from dexbench.experts.surface import FingerEnds, front_aim
from dexbench.tasks.plans import PushPlan

SPEED = 0.4  # m/s in the air
PUSH_SPEED = 0.25  # m/s while pushing
MIN_PUSH_SPEED = 0.04  # m/s at the end of a push
SLOW_DOWN = 0.15  # s: push speed is the push still to go over this
TURN_RATE = 3.0  # rad/s
TIP_RADIUS = 0.01  # m: a fingertip's half-width, the pusher's size
LOW = 0.018  # m above the table: the lowest fingertip (site) while pushing ...
# ... unless that presses the finger ends (their geoms' extreme points) further into the
# table than a resting contact sinks (~1 mm): a long distal link (Inspire's, LEAP's: 2.5-2.7
# cm past its site, against the Shadow hand's 1.9) would drag on the table and stall
ENDS_CLEAR = -0.001  # m above the table: the finger ends while pushing, at least
CLEAR = 0.05  # m above the block's top: the fingertips while travelling over it
STANDOFF = 0.02  # m between the fingertip and the outline before a push
EDGE_STEP = 0.01  # m between candidate contact points along the outline
CORNER_GAP = 0.012  # m: contact points keep this far from convex corners (and
# 1.5 fingertip radii from concave ones, where the fingertip would not fit)
PUSH_LENGTHS = np.array([0.004, 0.008, 0.015, 0.03, 0.06, 0.1])  # m past first contact
YAW_WEIGHT = 0.12  # m of position error that weigh as much as 1 rad of yaw error
NEAR = 0.025  # m: a next push starting this close to the fingertip needs no detour
ARRIVED = 0.006  # m: the commanded fingertip this close to a waypoint moves on
PUSH_DONE = 0.002  # m short of its length, a push has been made
LEAD = 0.05  # m the pushing command runs ahead of the fingertip
GIVE = 0.012  # m the fingertip lags its command while pushing the block
PUSH_OVERHEAD = 0.15  # s every push costs beyond its length, for choosing pushes
PUSH_SLACK = 0.3  # s a push may take beyond its length at PUSH_SPEED (a stuck push ends)
LIFT_DETOUR = 0.4  # m of extra travel a detour over the block counts as (rise, descend)
BAN_SECONDS = 1.0  # a stuck push's contact is left out of the choice this long
ROW_TILT = 0.25  # rad the fingertip row tilts, leading fingertip down: the others clear
MAX_YAW = 0.9 * np.pi  # a floating wrist's yaw joint stops at +-pi
HANG = np.pi / 2  # rad the fingers pitch down from level: straight down
# An arm may lean the hanging fingers out by up to this much where it cannot reach the
# push with them straight down (far from its base, its wrist at a limit).
LEANS = (0.0, 0.35, -0.35, 0.7, -0.7)


class Stage:
    """Each env's step in its push: plan, rise, over to the start, down, push; done."""

    PLAN, RISE, OVER, DOWN, PUSH, DONE = range(6)


def outline(rects: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Candidate contacts of a union of rectangles: points (K, 2) on its outer outline
    and inward push directions (K, 2), all in the body frame."""
    points, pushes = [], []
    for cx, cy, hx, hy in rects:
        for normal, tangent, half, span in (((1, 0), (0, 1), hx, hy), ((-1, 0), (0, 1), hx, hy),
                                            ((0, 1), (1, 0), hy, hx), ((0, -1), (1, 0), hy, hx)):
            n, t = np.array(normal, float), np.array(tangent, float)
            for s in np.arange(-span + CORNER_GAP, span - CORNER_GAP + 1e-9, EDGE_STEP):
                p = np.array([cx, cy]) + half * n + s * t
                clearance = p + n * (TIP_RADIUS + 1e-3)
                if inside_rects(clearance[None], rects, 0.0)[0]:
                    continue  # an inner edge, shared with the other rectangle
                room = p + n * (TIP_RADIUS + STANDOFF)
                if inside_rects(room[None], rects, 1.5 * TIP_RADIUS)[0]:
                    continue  # a concave corner too tight for the fingertip
                points.append(p)
                pushes.append(-n)
    return np.array(points), np.array(pushes)


def inside_rects(pts: np.ndarray, rects: np.ndarray, margin: float) -> np.ndarray:
    """(...,) whether points (..., 2) lie within `margin` of the union of rectangles."""
    rel = np.abs(pts[..., None, :] - rects[:, :2])
    return (rel <= rects[:, 2:] + margin).all(axis=-1).any(axis=-1)


def _rot2(yaw: np.ndarray) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


class PushExpert:
    """Greedy closed-loop pusher for the right hand of a single-hand env."""

    def __init__(self, env: DexEnv, plan: PushPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self._arm = env.embodiment.mount != "floating"
        self._leans = np.array(LEANS if self._arm else LEANS[:1])
        self._palm, self._tips = palm_and_finger_sites(env, side)
        self.rects = np.asarray(plan.rects, dtype=float)
        self.points, self.pushes = outline(self.rects)
        areas = 4 * self.rects[:, 2] * self.rects[:, 3]
        self.centroid = (areas[:, None] * self.rects[:, :2]).sum(0) / areas.sum()
        second = areas * ((self.rects[:, 2] ** 2 + self.rects[:, 3] ** 2) / 3 + (
            (self.rects[:, :2] - self.centroid) ** 2).sum(1))
        self.gyration2 = second.sum() / areas.sum()  # m^2
        hanging = palm_down(np.zeros(1)) @ pitch_down(HANG)
        self._row_yaw = float(np.arctan2(hanging[0, 1, 1], hanging[0, 0, 1]))
        n = env.num_envs
        self.tip = np.zeros((n, 3))  # commanded leading fingertip (world)
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.yaw = np.zeros(n)
        self.offsets = np.zeros((n, len(self._tips), 3))  # fingertips in the hand frame
        # where the fingertip links end (their geoms' extreme points), in the hand frame
        self._ends = FingerEnds(env, self._palm, self._tips)
        self.surface = np.zeros((n, self._ends.count, 3))
        self.aim = np.zeros((n, 3))  # the point the push steers, in the hand frame
        self.lead = np.zeros(n, dtype=np.int64)
        self.stage = np.full(n, Stage.PLAN)
        self.start = np.zeros((n, 3))  # fingertip before the push (world)
        self.direction = np.zeros((n, 3))
        self.length = np.zeros(n)  # m the fingertip goes from `start` along the push
        self.timer = np.zeros(n)  # s into the push
        self.choice = np.zeros(n, dtype=np.int64)  # candidate contact being pushed
        self.banned = np.zeros(n, dtype=np.int64)  # candidate whose push got stuck
        self.ban_timer = np.zeros(n)
        self.tilt = np.zeros(n)
        self.lean = np.zeros(n)  # rad the fingers lean out of straight down (arms only)
        self.drop = np.zeros(n)  # m the leading fingertip is above the lowest one (or more)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        palm = pos[ids]
        self.offsets[ids] = tips[ids]
        self.surface[ids] = self._ends()[ids]
        self.rot[ids] = rot[ids]
        self.lead[ids] = 0
        self.aim[ids] = self.offsets[ids, 0]
        self.tip[ids] = palm + np.einsum("nij,nj->ni", rot[ids], self.aim[ids])
        self.yaw[ids] = 0.0
        self.stage[ids] = Stage.PLAN
        self.ban_timer[ids] = 0.0
        self.adapter.reset(ids)

    def act(self) -> torch.Tensor:
        done = np.asarray(self.plan.done(self.env), dtype=bool)
        self.stage[done] = Stage.DONE
        self.stage[(self.stage == Stage.DONE) & ~done] = Stage.PLAN
        planning = np.flatnonzero(self.stage == Stage.PLAN)
        if len(planning):
            self._plan(planning)
        low = TABLE_TOP_Z + LOW
        high = TABLE_TOP_Z + self.plan.height + CLEAR
        target_rot = self._hanging(self.yaw, self.tilt, self.lean)
        # Turning about a low fingertip would sweep the other fingers over the table.
        hold = (self.stage == Stage.RISE) & (self.tip[:, 2] < high - ARRIVED)
        target_rot[hold] = self.rot[hold]
        target = self.tip.copy()
        speed = np.full(len(target), SPEED)
        rise = self.stage == Stage.RISE
        target[rise, 2] = high
        over = self.stage == Stage.OVER
        target[over] = self.start[over]
        target[over, 2] = high
        down = self.stage == Stage.DOWN
        target[down] = self.start[down]
        target[down, 2] = low + self.drop[down]
        push = self.stage == Stage.PUSH
        palm_now, rot_now = site_pose(self.env, self._palm)
        actual = palm_now + np.einsum("nij,nj->ni", rot_now, self.aim)
        # The fingertip gives a little under load: the command runs ahead of it, a bit.
        ahead = ((actual - self.start) * self.direction).sum(axis=1)
        target[push] = self.start[push] + self.direction[push] * np.minimum(
            ahead[push] + LEAD, self.length[push] + GIVE)[:, None]
        target[push, 2] = low + self.drop[push]
        # Slowing down towards the push's end: the block stops where planned.
        speed[push] = np.clip((self.length - ahead)[push] / SLOW_DOWN, MIN_PUSH_SPEED, PUSH_SPEED)
        self.timer[push] += self.env.control_dt
        target[self.stage == Stage.DONE, 2] = high
        turned = self._turn(self._hanging(self.yaw, self.tilt, self.lean)) < 0.05
        self.tip, self.rot = step_towards(self.tip, self.rot, target, target_rot,
                                          (speed * self.env.control_dt)[:, None],
                                          TURN_RATE * self.env.control_dt)
        arrived = np.linalg.norm(self.tip - target, axis=1) < ARRIVED
        self.stage[rise & arrived] = Stage.OVER
        arrived &= turned
        self.stage[over & arrived] = Stage.DOWN
        self.stage[down & arrived] = Stage.PUSH
        over_time = self.timer > self.length / PUSH_SPEED + PUSH_SLACK
        ended = push & ((ahead >= self.length - PUSH_DONE) | over_time)
        self.tip[ended] = actual[ended]
        self.stage[ended] = Stage.PLAN
        # A push that got nowhere is not tried again for a while.
        stuck = ended & over_time & (ahead < self.length / 2)
        self.banned[stuck] = self.choice[stuck]
        self.ban_timer[stuck] = BAN_SECONDS
        self.ban_timer -= self.env.control_dt
        palm = self.tip - np.einsum("nij,nj->ni", self.rot, self.aim)
        closure = np.zeros(self.env.num_envs)
        return self.adapter.actions({self.side: HandCommand(palm, self.rot, closure)})

    def _plan(self, ids: np.ndarray) -> None:
        """Choose each env's next push: where, which way and how far."""
        view = self.env.view
        body = self.env.task.objects[self.plan.obj].root
        pos = view.body_pos(body).cpu().numpy()[ids, :2]
        yaw = body_yaw(view.body_quat(body).cpu().numpy()[ids])
        goal = np.asarray(self.plan.goal(self.env))[ids]
        rot, goal_rot = _rot2(yaw), _rot2(goal[:, 2])
        centre = pos + rot @ self.centroid
        goal_centre = goal[:, :2] + goal_rot @ self.centroid
        points = pos[:, None] + np.einsum("nij,kj->nki", rot, self.points)
        pushes = np.einsum("nij,kj->nki", rot, self.pushes)
        lever = points - centre[:, None]
        moment = lever[..., 0] * pushes[..., 1] - lever[..., 1] * pushes[..., 0]
        share = 1.0 / (1.0 + moment ** 2 / self.gyration2)  # of the push that translates
        lengths = PUSH_LENGTHS[None, None]
        moved = centre[:, None, None] + (share[..., None] * lengths)[..., None] * pushes[
            :, :, None]
        turned = yaw[:, None, None] + (share * moment / self.gyration2)[..., None] * lengths
        cost_now = self._cost(centre, yaw, goal_centre, goal[:, 2])
        cost = self._cost(moved, turned, goal_centre[:, None, None], goal[:, 2, None, None])
        # A fingertip already behind the contact line pushes on from where it is.
        behind = ((points - self.tip[ids, None, :2]) * pushes).sum(-1) - TIP_RADIUS
        gap = np.where(behind >= 0.0, np.minimum(behind, STANDOFF), STANDOFF)
        start = points - pushes * (TIP_RADIUS + gap)[..., None]
        travel = np.linalg.norm(start - self.tip[ids, None, :2], axis=-1)
        gap = np.where(travel < NEAR, gap, STANDOFF)
        start = points - pushes * (TIP_RADIUS + gap)[..., None]
        travel = np.linalg.norm(start - self.tip[ids, None, :2], axis=-1)
        detour = np.where(travel < NEAR, 0.0, LIFT_DETOUR)
        seconds = (travel + detour)[..., None] / SPEED + (
            gap[..., None] + lengths + GIVE) / PUSH_SPEED + PUSH_OVERHEAD
        gain = (np.sqrt(cost_now)[:, None, None] - np.sqrt(cost)) / seconds
        banned = self.ban_timer[ids] > 0
        gain[np.flatnonzero(banned), self.banned[ids][banned]] = -np.inf
        best = gain.reshape(len(ids), -1).argmax(axis=1)
        k, m = np.unravel_index(best, gain.shape[1:])
        rows = np.arange(len(ids))
        d = pushes[rows, k]
        self.choice[ids] = k
        self.start[ids, :2] = start[rows, k]
        self.direction[ids] = np.column_stack([d, np.zeros(len(ids))])
        self.length[ids] = gap[rows, k] + PUSH_LENGTHS[m]
        self.timer[ids] = 0.0
        self._face(ids, d)
        clear = travel[rows, k] < NEAR
        self.stage[ids] = np.where(clear, Stage.DOWN, Stage.RISE)

    def _cost(self, centre: np.ndarray, yaw: np.ndarray, goal_centre: np.ndarray,
              goal_yaw: np.ndarray) -> np.ndarray:
        """Squared pose error (m^2), yaw weighed by YAW_WEIGHT."""
        return ((centre - goal_centre) ** 2).sum(-1) + (YAW_WEIGHT * wrap(yaw - goal_yaw)) ** 2

    def _face(self, ids: np.ndarray, d: np.ndarray) -> None:
        """Turn the fingertip row along pushes `d` (n, 2), the nearer of its two yaws,
        tilted the way that drops its leading fingertip (the one ahead along the push)
        least. On an arm, only among the turns and leans whose push the arm can take
        (`ActionAdapter.reach_cost` within `REACH_MARGIN` of the best), the least lean first: a
        wrist at its limit leaves the fingertip far from the line it meant to push along."""
        along = np.arctan2(d[:, 1], d[:, 0]) - self._row_yaw
        options = np.stack([wrap(along), wrap(along + np.pi)], axis=1)
        tilts = np.array([ROW_TILT, -ROW_TILT])
        far = np.abs(wrap(options - self.yaw[ids, None]))
        far[np.abs(options) > MAX_YAW] = np.inf
        push = np.column_stack([d, np.zeros(len(ids))])
        rows = np.arange(len(ids))
        shape = (len(ids), 2, len(tilts), len(self._leans))
        leads, drops = np.zeros(shape, dtype=np.int64), np.zeros(shape)
        for j, k, m in np.ndindex(shape[1:]):
            hang = self._hanging(options[:, j], np.full(len(ids), tilts[k]),
                                 np.full(len(ids), self._leans[m]))
            tips = np.einsum("nij,nkj->nki", hang, self.offsets[ids])
            ends = np.einsum("nij,nkj->nki", hang, self.surface[ids])
            leads[:, j, k, m] = (tips @ push[:, :, None])[..., 0].argmax(axis=1)
            lead_z = tips[rows, leads[:, j, k, m], 2]
            drops[:, j, k, m] = np.maximum(lead_z - tips[..., 2].min(axis=1), lead_z
                                           - ends[..., 2].min(axis=1) + ENDS_CLEAR - LOW)
        # the yaw's distance first, then the lean, then the drop (floating: no leans)
        rank = (far[:, :, None, None] * 1e3 + np.abs(self._leans) * 10.0 + drops)
        if self._arm:
            cost = self._reach(ids, options, tilts, leads, drops)
            cost[np.broadcast_to(np.isinf(far)[:, :, None, None], shape)] = np.inf
            best = cost.reshape(len(ids), -1).min(axis=1)[:, None, None, None]
            rank = rank + np.where(cost <= best + REACH_MARGIN, 0.0, np.inf)
        best = rank.reshape(len(ids), -1).argmin(axis=1)
        j, k, m = np.unravel_index(best, shape[1:])
        self.yaw[ids] = options[rows, j]
        self.tilt[ids] = tilts[k]
        self.lean[ids] = self._leans[m]
        self.drop[ids] = drops[rows, j, k, m]
        lead = leads[rows, j, k, m]
        palm = self.tip[ids] - np.einsum("nij,nj->ni", self.rot[ids], self.aim[ids])
        self.lead[ids] = lead
        hang = self._hanging(self.yaw[ids], self.tilt[ids], self.lean[ids])
        for r, i in enumerate(ids):
            self.aim[i] = self._aim(i, hang[r], push[r])
        self.tip[ids] = palm + np.einsum("nij,nj->ni", self.rot[ids], self.aim[ids])

    def _aim(self, i: int, hang: np.ndarray, push: np.ndarray) -> np.ndarray:
        """The leading finger's point the push steers (hand frame; `surface.front_aim`):
        its front where it meets the block's side. Steering the tip site, the planned
        pushes (a few millimetres at the end) fell short or went beside their point."""
        lo, hi = self._ends.rows[self.lead[i]]
        site = hang @ self.offsets[i, self.lead[i]]
        points = self.surface[i, lo:hi] @ hang.T
        rise = points[:, 2] - site[2] + LOW + self.drop[i]  # over the table, pushing
        level = (rise >= 0.0) & (rise <= self.plan.height)
        return hang.T @ front_aim(site, points, level, push, TIP_RADIUS)

    def _reach(self, ids: np.ndarray, options: np.ndarray, tilts: np.ndarray,
               leads: np.ndarray, drops: np.ndarray) -> np.ndarray:
        """(n, yaw, tilt, lean) how badly the arm misses the push (its start and end palm
        poses) with each yaw option, tilt and lean (`ActionAdapter.reach_cost`)."""
        low = TABLE_TOP_Z + LOW
        cost = np.zeros(leads.shape)
        for r, i in enumerate(ids):
            for j, k, m in np.ndindex(leads.shape[1:]):
                rot = self._hanging(options[r:r + 1, j], tilts[k:k + 1], self._leans[m:m + 1])[0]
                start = self.start[i].copy()
                start[2] = low + drops[r, j, k, m]
                end = start + self.direction[i] * self.length[i]
                offset = rot @ self.offsets[i, leads[r, j, k, m]]
                cost[r, j, k, m] = self.adapter.reach_cost(
                    self.side, int(i), [(start - offset, rot), (end - offset, rot)])
        return cost

    @staticmethod
    def _hanging(yaw: np.ndarray, tilt: np.ndarray, lean: np.ndarray | None = None
                 ) -> np.ndarray:
        """(N, 3, 3) hand frames, fingers down (leaning `lean` rad, default none, out
        of vertical), turned `yaw` about world z and the fingertip row tilted `tilt` (rad)
        about the palm normal."""
        lean = np.zeros(len(tilt)) if lean is None else lean
        c, s = np.cos(tilt), np.sin(tilt)
        roll = np.zeros((len(tilt), 3, 3))
        roll[:, 0, 0], roll[:, 0, 1], roll[:, 1, 0], roll[:, 1, 1], roll[:, 2, 2] = c, -s, s, c, 1
        pitch = np.stack([pitch_down(HANG - a) for a in lean])
        return palm_down(yaw) @ pitch @ roll

    def _turn(self, target_rot: np.ndarray) -> np.ndarray:
        """Angle (rad) still to turn from the commanded to the target orientation."""
        return rotation_angle(self.rot, target_rot)
