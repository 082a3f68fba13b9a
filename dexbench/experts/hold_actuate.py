"""Hold and actuate: one hand pushes a part along its joint, the other holds the object.

For free articulated objects (a folder's flap, a stapler's arm, a knife's blade slider,
a scissor ring). The other hand runs its own plan (typically a press pinning the object
to the table); once its finger tips are over their point, the pushing hand comes in beside
the driven point, on the side it pushes from, and keeps its finger pads a little ahead
of the point along the joint's motion (the arc about a hinge, the line of a slide) until
the joint has covered the plan's `done` fraction (finger tips too thick for the gap under
an edge they lift aim further in, towards the hinge: `wedge_depth`; a finger row stepped
along the palm normal is rolled level first: `level_row`). There it stays, or,
releasing, rises back and levels the hand (a hanging hand is near the floating wrist's
gimbal lock, bad for whatever step comes next). Without a hold plan the other hand moves
out of the way (outwards and up), or, with a `then` plan (picking the object up once its part has
moved), waits outwards of and above that plan's point and runs it once the joint is
done and a releasing pusher has backed off; that pusher then goes on outwards and up, out
of the way of the other arm reaching in (on arms the two wrists and forearms otherwise
meet over the object). Contact points are measured on the hands (mean finger tips), so
the script serves every hand and mount.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np
import torch

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.embodiments.hand_geometry import fingertip_thickness
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import (
    ActionAdapter,
    HandCommand,
    palm_and_finger_sites,
    site_pose,
    tips_in_palm_frame,
)
from dexbench.experts.base import Expert, host_ids
from dexbench.experts.motion import body_yaw, palm_down, pitch_down, step_towards, turned
from dexbench.tasks.plans import HoldActuatePlan, locate

SPEED = 0.4  # m/s in the air
PUSH_SPEED = 0.1  # m/s onto the point and along the joint's motion
TURN_RATE = 3.0  # rad/s
HOVER = 0.08  # m back along the approach before going in beside the point
LEAD = 0.03  # m the pads aim ahead of the point
BESIDE = 0.025  # m the pads start from the point: behind it, or out along the approach
ARRIVED = 0.01  # m
HELD = 0.02  # m across from the holding point to the holding hand's pressing finger tips
# m above its point the holding hand's pressing finger tips may rest, over it, and hold: a
# hand whose wrist meets the table first (Shadow's forearm, pressing the stapler's hinge block)
# stops there, and would otherwise keep the pusher waiting; one coming down from its hover
# point (`press.HOVER`, 8 cm) is on it before the pusher is
RESTS_ABOVE = 0.035
ASIDE = 0.12  # m an idle other hand moves outwards and up, out of the pusher's way
# m outwards of and above its point the `then` hand waits (its wrist clear of the pusher's)
WAIT_OUT, WAIT_UP = 0.22, 0.12
CLEAR_OUT, CLEAR_UP = 0.15, 0.3  # m a released pusher then moves outwards and up
UP = np.array([0.0, 0.0, 1.0])
LEVEL = 1e-3  # trace(R1^T R2) this close to 3: the hand has turned level
# rad above level a finger tip's contact with an edge's corner must face for the tip,
# rising, to carry the corner up rather than slide past it: beyond the friction cone
# (friction 1, MuJoCo's default, the tips' and the parts') about the vertical
SLIDES_BELOW = np.pi / 4
PUSH_POSES = 4  # palm poses along the push that `push_poses` gives, its start and end included


def level_row(tips: np.ndarray) -> np.ndarray:
    """(N, 3, 3) turns about the hand's x axis (along the fingers) that bring the finger
    tips (N, K, 3, in the hand frame) level across the hand: the plan centres the pads in
    the gap under an edge, and a row whose tips step towards the palm normal from finger
    to finger (LEAP's, 14 mm from index to ring, open) adds that step to the tips'
    thickness, so its highest tip's back met the folder's flap edge from above and pressed
    it shut. Identity for a level row (Shadow, Allegro)."""
    y, z = tips[..., 1], tips[..., 2]
    y, z = y - y.mean(axis=1, keepdims=True), z - z.mean(axis=1, keepdims=True)
    slope = np.arctan((y * z).sum(axis=1) / np.maximum((y * y).sum(axis=1), 1e-12))
    return turned(np.tile([1.0, 0.0, 0.0], (len(slope), 1)), -slope)


def wedge_depth(thickness: float, height: np.ndarray) -> np.ndarray:
    """(N,) m the pads aim past their point, towards the hinge, where the point (the pads'
    centre, under the edge they lift) stands `height` (N,) above the table.

    The plan centres the pads in the gap under the edge, 2 `height` tall. A finger tip
    `thickness` thick (radius r, its site at its centre) fits in it; a thicker one, lying
    on the table, meets the edge's lower corner on its upper front and stops with its
    centre sqrt(r^2 - (2 height - r)^2) out from the point. Lifting, it carries the corner
    up if their contact faces up more steeply than `SLIDES_BELOW` (Inspire's 17 mm tips
    under the stapler's lip, 16 mm up: 65 deg), else it slides up the part's face and the
    joint never moves (Allegro's 24 mm tips: 19 deg, 11 mm out, as measured). Those aim
    that much further in, which drives them on in under the corner, and it rides up on
    them (OpenStapler, bimanual_floating_allegro: 0.0 -> 0.9). Zero for a tip that fits,
    and where the edge is no higher than the tip's centre (pushing in presses it down)."""
    r, above = thickness / 2, 2 * np.asarray(height) - thickness / 2
    wedged = (above > 0.0) & (above < r * np.sin(SLIDES_BELOW))
    return np.where(wedged, np.sqrt(np.maximum(r**2 - above**2, 0.0)), 0.0)


class HoldActuateExpert:
    """Push the plan's point along its joint with `plan.side`; the hold plan runs on the
    other hand (`build(plan, side)` makes its expert)."""

    def __init__(self, env: DexEnv, plan: HoldActuatePlan,
                 build: Callable[[object, str], Expert]) -> None:
        self.env, self.plan = env, plan
        self.adapter = ActionAdapter(env)
        model = env.scene.model
        self._palm, self._tips = palm_and_finger_sites(env, plan.side)
        self.body, self.local = locate(env.task.objects, plan.obj, plan.point)
        self.root = env.task.objects[plan.obj].root
        joint = model.joint(plan.joint)
        self._slide = joint.type[0] == mujoco.mjtJoint.mjJNT_SLIDE
        self._joint_body = model.body(joint.bodyid[0]).name
        self._joint_axis, self._joint_pos = tuple(joint.axis), tuple(joint.pos)
        self.other = next((s for s in env.embodiment.sides if s != plan.side), None)
        self.holder = build(plan.hold, self.other) if plan.hold is not None else None
        self.after = build(plan.then, self.other) if plan.then is not None else None
        if self.after is not None:
            self._then_at = locate(env.task.objects, plan.then.obj, plan.then.point)
        self._other_cols = [i for i, a in enumerate(env.embodiment.actuators)
                            if a.startswith(f"{self.other}/")]
        if self.holder is not None:
            self._hold_at = locate(env.task.objects, plan.hold.obj, plan.hold.point)
        n = env.num_envs
        eye = np.repeat(np.eye(3)[None], n, axis=0)
        self.pos, self.rot, self.level = np.zeros((n, 3)), eye.copy(), eye.copy()
        self.pads = np.zeros((n, 3))  # finger pads in the hand frame
        self.roll = eye.copy()  # levels the finger row under an edge: `level_row`
        self.into = np.zeros(n)  # m the pads aim past the point, towards the hinge
        # fingers under an edge lifting a hinged part: their row is levelled and tips too
        # thick for the gap aim further in (measured once per hand, only for these plans)
        self._under_edge = plan.yaw is not None and not self._slide
        self._tip = (fingertip_thickness(env.embodiment.hand.name, plan.side)
                     if self._under_edge else 0.0)
        self.stage = np.zeros(n, dtype=np.int64)  # hover, beside, on, push, done
        self.away = np.zeros(n, dtype=bool)  # released: back at the hover point
        self.started = np.zeros(n, dtype=bool)  # the other hand runs `then`
        self.aside = (np.zeros((n, 3)), eye.copy())  # where an idle other hand waits
        self.clear = np.zeros((n, 3))  # the released pusher's move aside; risen: its goal
        if self.other is not None:
            self._other_palm = model.site(env.embodiment.sides[self.other].palm_site).id

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.pads[ids] = tips[ids].mean(axis=1)
        if self._under_edge:
            self.roll[ids] = level_row(tips[ids])
            height = self.env.view.point_pos(self.body, self.local).cpu().numpy()[ids, 2]
            self.into[ids] = wedge_depth(self._tip, height - TABLE_TOP_Z)
        self.stage[ids], self.away[ids], self.started[ids] = 0, False, False
        self.adapter.reset(ids)
        if self.holder is not None:
            self.holder.reset(env_ids)
        elif self.other is not None:
            pos, rot = site_pose(self.env, self._other_palm)
            out = np.sign(pos[ids, 1:2] - self.pos[ids, 1:2]) * [0.0, 1.0, 0.0]
            self.aside[0][ids], self.aside[1][ids] = pos[ids] + ASIDE * (out + UP), rot[ids]
            if self.after is not None:  # nearer: outwards of and above where it starts
                then = self.env.view.point_pos(*self._then_at).cpu().numpy()
                self.aside[0][ids] = then[ids] + WAIT_OUT * out + WAIT_UP * UP
                self.clear[ids] = CLEAR_UP * UP - CLEAR_OUT * out

    def _held(self) -> np.ndarray:
        """(N,) the holding hand's pressing finger tips are over its point, at most
        `RESTS_ABOVE` above it (always, without one)."""
        if self.holder is None:
            return np.ones(self.env.num_envs, dtype=bool)
        off = self.holder.pressing_tips() - self.env.view.point_pos(*self._hold_at).cpu().numpy()
        return (np.linalg.norm(off[:, :2], axis=1) < HELD) & (off[:, 2] < RESTS_ABOVE)

    def _done(self) -> np.ndarray:
        done = self.env.task.joint_progress(self.env.view, self.plan.joint) >= self.plan.done
        return done.cpu().numpy()

    @property
    def finished(self) -> np.ndarray:
        if self.after is not None:
            return self.started & np.asarray(self.after.finished)
        if not self.plan.release:
            return self.stage == 4
        return self.away & (np.einsum("nij,nij->n", self.rot, self.level) > 3.0 - LEVEL)

    def _motion(self, point: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) unit directions the joint moves `point` in, towards the push, and from
        the hinge's axis out to `point` (zero on a slide)."""
        view = self.env.view
        axis = view.axis(self._joint_body, self._joint_axis).cpu().numpy()
        if self._slide:
            return self.plan.direction * axis, np.zeros_like(axis)
        radial = point - view.point_pos(self._joint_body, self._joint_pos).cpu().numpy()
        radial -= (radial * axis).sum(axis=1, keepdims=True) * axis
        radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-9)
        return self.plan.direction * np.cross(axis, radial), radial

    def _hand(self, point: np.ndarray, push: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(N, 3, 3) heading (palm down, fingers along the hand's yaw) and pushing hand
        frames; (N, 3) or (3,) the direction it comes in from, and (N, 3) where its pads
        start beside `point` (N, 3) moving along `push` (N, 3)."""
        view = self.env.view
        if self.plan.yaw is None:  # fingers hanging, pads facing the push
            heading = palm_down(np.arctan2(-push[:, 1], -push[:, 0]))
            return (heading, heading @ pitch_down(np.pi / 2), np.array([0.0, 0.0, 1.0]),
                    point - BESIDE * push)
        heading = palm_down(body_yaw(view.body_quat(self.root).cpu().numpy()) + self.plan.yaw)
        approach = view.axis(self.root, self.plan.approach).cpu().numpy()
        return (heading, heading @ pitch_down(self.plan.pitch) @ self.roll, approach,
                point + BESIDE * approach / np.linalg.norm(approach, axis=1, keepdims=True))

    def push_poses(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The palm poses ((N, 3), (N, 3, 3)) of the push: its pads on the point now, then
        carrying it through the rest of the joint's `done` travel (`PUSH_POSES` in all),
        as if the part moved alone: what a mount must take for the push
        (`ActionAdapter.reach_cost`)."""
        view, task = self.env.view, self.env.task
        now = view.point_pos(self.body, self.local).cpu().numpy()
        lo, hi = task.joint_range(self.plan.joint)
        start = task.initial_joints[self.plan.joint]
        left = np.maximum(self.plan.done - task.joint_progress(view, self.plan.joint)
                          .cpu().numpy(), 0.0) * max(start - lo, hi - start)
        axis = view.axis(self._joint_body, self._joint_axis).cpu().numpy()
        hinge = view.point_pos(self._joint_body, self._joint_pos).cpu().numpy()
        poses = []
        for share in np.linspace(0.0, 1.0, PUSH_POSES):
            travel = self.plan.direction * share * left
            if self._slide:
                point = now + travel[:, None] * axis
            else:
                point = hinge + np.einsum("nij,nj->ni", turned(axis, travel), now - hinge)
            push, radial = self._motion(point)
            _, rot, _, _ = self._hand(point, push)
            pads = np.einsum("nij,nj->ni", rot, self.pads)
            poses.append((point - self.into[:, None] * radial - pads, rot))
        return poses

    def act(self) -> torch.Tensor:
        view = self.env.view
        point = view.point_pos(self.body, self.local).cpu().numpy()
        push, radial = self._motion(point)
        heading, rot, approach, beside = self._hand(point, push)
        into = self.into[:, None] * radial
        goals = (beside + HOVER * approach, beside, point - into, point + LEAD * push - into)
        pads = np.einsum("nij,nj->ni", rot, self.pads)
        target = np.stack([goals[min(s, 3)][i] for i, s in enumerate(self.stage)]) - pads
        arrived = np.linalg.norm(self.pos - target, axis=1) < ARRIVED
        self.stage[arrived & (self.stage < 3) & ((self.stage > 0) | self._held())] += 1
        self.stage[(self.stage == 3) & self._done()] = 4
        done = self.stage == 4
        if self.plan.release:  # up, then level: a hanging hand is near the wrist's gimbal lock
            target[done] = (goals[0] - pads)[done]
            up = ~self.away & done & (np.linalg.norm(self.pos - target, axis=1) < ARRIVED)
            self.away |= up
            self.level[up] = heading[up]
            rot[self.away] = self.level[self.away]
            if self.after is not None:
                self.clear[up] += self.pos[up]
                target[self.away] = self.clear[self.away]
        else:
            target[done] = self.pos[done]
        pushing = (self.stage >= 2) & (self.stage < 4)
        speed = np.where(pushing, PUSH_SPEED, SPEED)[:, None] * self.env.control_dt
        self.pos, self.rot = step_towards(self.pos, self.rot, target, rot, speed,
                                          TURN_RATE * self.env.control_dt)
        commands = {self.plan.side: HandCommand(self.pos, self.rot, np.zeros(len(point)))}
        if self.holder is None and self.other is not None:  # the idle hand makes room
            commands[self.other] = HandCommand(*self.aside, np.zeros(len(point)))
        actions = self.adapter.actions(commands)
        if self.holder is not None:
            actions[:, self._other_cols] = self.holder.act()[:, self._other_cols]
        if self.after is not None:  # once the joint is done and a releasing pusher clear
            start = (self.away if self.plan.release else done) & ~self.started
            if start.any():
                self.after.reset(torch.as_tensor(np.flatnonzero(start)))
                self.started |= start
            if self.started.any():
                rows = torch.as_tensor(np.flatnonzero(self.started))[:, None]
                actions[rows, self._other_cols] = self.after.act()[rows, self._other_cols]
        return actions
