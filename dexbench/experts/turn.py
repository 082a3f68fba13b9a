"""Turn a hinged part: push its tip around its hinge with the fingers.

For faucet levers and dials (vertical hinge: the hand hangs its fingers beside the tip,
pads facing the way it must go, or leans them out along the tip's radius, or in towards
the hinge, to reach it from an arm) and lids (horizontal hinge: palm-down fingers, tilted
down, slide under the free edge). Either way the fingers keep a little ahead of the tip
along its arc until the task succeeds. A part whose tip repeats round the hinge (a cap's
fins) is turned in strokes: push one copy a period round, lift, come down behind the
next. The contact point is measured on the hand itself (mean fingertip), so the script
serves every hand and mount.
"""

from __future__ import annotations

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
from dexbench.experts.motion import (
    TRAVEL_RISE,
    body_yaw,
    palm_down,
    pitch_down,
    step_towards,
    turned,
    via_travel,
)
from dexbench.tasks.plans import TurnPlan, locate

SPEED = 0.4  # m/s in the air
TURN_RATE = 3.0  # rad/s the hand turns at most
HOVER = 0.08  # m above the lever before going down beside it
LEAD = 0.03  # m the pads aim ahead of the tip along the arc
BESIDE = 0.025  # m the pads start behind the tip, on the side they push from
MISSED = 15  # control steps at their aim ahead of a copy that no longer moves: missed it


class TurnExpert:
    """Go down beside the lever tip, then push it along its arc."""

    def __init__(self, env: DexEnv, plan: TurnPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        model = env.scene.model
        self._palm, self._tips = palm_and_finger_sites(env, side)
        info = env.task.objects[plan.obj]
        self.body, self.tip = locate(env.task.objects, plan.obj, plan.tip)
        self.frame = info.root
        hinge = plan.hinge or next(iter(info.joints))
        self._hinge, self._limits = hinge, model.jnt_range[model.joint(hinge).id]
        self._hinge_body = model.body(model.joint(hinge).bodyid[0]).name
        self._hinge_axis = tuple(model.joint(hinge).axis)
        n = env.num_envs
        self.pos = np.zeros((n, 3))
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.pads = np.zeros((n, 3))  # finger pads in the hand frame
        self.stage = np.zeros(n, dtype=np.int64)  # 0 hover, 1 down beside, 2 push, 3 lift
        self.direction = np.full(n, plan.direction)
        # With a `period`: the copy of the tip pushed now (copies behind the tip's own,
        # in the push direction), the first one pushed, and the joint value at reset.
        self.copy = np.zeros(n, dtype=np.int64)
        self.first = np.zeros(n, dtype=np.int64)
        self.q0 = np.zeros(n)
        self.lift_from = np.zeros((n, 3))
        self.into = np.zeros(n)
        self.waiting = np.zeros(n, dtype=np.int64)  # steps the pads have been at their aim
        # With `pitch`, the hover (low, in front of an edge) is reached over the top, at
        # least this high: from an arm's start beside the object a straight line drags
        # the tilted fingers across it (a laptop's lid pressed shut before they reach its
        # edge). Hanging fingers come down from above their tip anyway.
        self.travel_z = np.zeros(n)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.pads[ids] = tips[ids].mean(axis=1)
        self.stage[ids], self.waiting[ids] = 0, 0
        self.travel_z[ids] = pos[ids, 2] + TRAVEL_RISE
        tip, pivot, axis, q = self._hinge_state()
        if self.plan.direction == 0.0:
            gap = [np.linalg.norm(_turn(pivot, axis, end - q, tip) - pos, axis=1)
                   for end in self._limits]
            # The way whose end leaves the tip nearer the palm's start: a hand on an arm
            # then pushes towards its base, not out of its reach.
            self.direction[ids] = np.where(gap[1] <= gap[0], 1.0, -1.0)[ids]
        self.q0[ids] = q[ids]
        if self.plan.period is not None:
            # Every stroke pushes a copy through the same period of arc (the zone), centred
            # where the leaning fingers point away from the palm's start (the far side for
            # fingers leaning out, the near side for fingers leaning in), as an arm reaches
            # best; for hanging fingers the zone starts at the tip. The first stroke takes
            # the copy inside the zone, `into` it, from where it is to the zone's end.
            period = self.plan.period
            radial, tangent = self._radial_tangent(tip, pivot, axis)
            away = np.sign(self.plan.lean) * (pivot - pos)
            into = np.where(self.plan.lean == 0.0, 0.0, np.mod(period / 2 - np.arctan2(
                (away * tangent).sum(axis=1), (away * radial).sum(axis=1)), 2 * np.pi))
            self.copy[ids] = self.first[ids] = (into // period).astype(np.int64)[ids]
            self.into[ids] = np.mod(into, period)[ids]
        self.adapter.reset(ids)

    def _hinge_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(N, 3) tip, hinge anchor and axis, and (N,) the joint's value in every env."""
        view = self.env.view
        return (view.point_pos(self.body, self.tip).cpu().numpy(),
                view.body_pos(self._hinge_body).cpu().numpy(),
                view.axis(self._hinge_body, self._hinge_axis).cpu().numpy(),
                view.joint_pos(self._hinge).cpu().numpy())

    def _radial_tangent(self, point: np.ndarray, pivot: np.ndarray, axis: np.ndarray,
                        ) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) unit directions out from the hinge axis to `point` and along its arc
        the way it is pushed."""
        radial = point - pivot
        radial -= (radial * axis).sum(axis=1, keepdims=True) * axis
        radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-9)
        return radial, self.direction[:, None] * np.cross(axis, radial)

    def act(self) -> torch.Tensor:
        view = self.env.view
        tip, pivot, axis, q = self._hinge_state()
        period = self.plan.period
        if period is not None:
            tip = _turn(pivot, axis, -self.direction * self.copy * period, tip)
            # A stroke ends once its copy reaches the zone's end.
            swept = self.direction * (q - self.q0) - (self.copy - self.first) * period
            done = (self.stage == 2) & (swept + self.into >= period)
            self.stage[done] = 3
            # Lift straight off from where the pads are, not chasing the copy round.
            self.lift_from[done] = (self.pos + np.einsum("nij,nj->ni", self.rot, self.pads))[done]
        radial, tangent = self._radial_tangent(tip, pivot, axis)
        if self.plan.pitch is None:
            # Fingers hanging, pads (palm side) facing the push direction.
            yaw = np.arctan2(-tangent[:, 1], -tangent[:, 0])
            rot = turned(np.cross(radial, axis), self.plan.lean) @ palm_down(yaw) @ pitch_down(
                np.pi / 2)
        else:
            rot = palm_down(body_yaw(view.body_quat(self.frame).cpu().numpy())) @ pitch_down(
                self.plan.pitch)
        approach = view.axis(self.frame, self.plan.approach).cpu().numpy()
        # Past the tip along the fingers (the hand's x axis), under a lid's edge.
        under = tip + self.plan.under * rot[:, :, 0]
        beside = under - BESIDE * tangent
        ahead = under + LEAD * tangent
        pads_world = np.einsum("nij,nj->ni", rot, self.pads)
        goal = {0: beside + HOVER * approach, 1: beside, 2: ahead,
                3: self.lift_from + HOVER * approach}
        aim = np.stack([goal[int(s)][i] for i, s in enumerate(self.stage)])
        close = np.linalg.norm(self.pos - (aim - pads_world), axis=1) < 0.01
        lifted = (self.stage == 3) & close
        self.waiting = np.where((self.stage == 2) & close, self.waiting + 1, 0)
        self.stage[(self.stage < 2) & close] += 1
        if period is not None:
            # Lifted off: back over the next copy, now at the zone's start, or over the
            # same one where the pads waited ahead of it, not moving it (they missed it).
            self.copy[lifted & (swept + self.into >= period)] += 1
            self.stage[lifted] = 0
            missed = self.waiting >= MISSED
            self.lift_from[missed] = (self.pos + np.einsum("nij,nj->ni", self.rot,
                                                           self.pads))[missed]
            self.stage[missed] = 3
        speed = np.where(self.stage == 2, self.plan.push_speed, SPEED)[:, None]
        speed, turn = speed * self.env.control_dt, TURN_RATE * self.env.control_dt
        if period is None:
            palm = aim - pads_world
            if self.plan.pitch is not None:
                out = self.stage == 0
                waypoint, low = via_travel(self.pos, palm,
                                           np.maximum(self.travel_z, palm[:, 2]))
                palm[out], rot[out & low] = waypoint[out], self.rot[out & low]
            self.pos, self.rot = step_towards(self.pos, self.rot, palm, rot, speed, turn)
        else:
            # Stroke after stroke the hand swings round the part, its palm far out: the
            # speed limits hold at the pads, and the palm swings round as fast as it turns.
            pads, self.rot = step_towards(
                self.pos + np.einsum("nij,nj->ni", self.rot, self.pads), self.rot, aim, rot,
                speed, turn)
            self.pos = pads - np.einsum("nij,nj->ni", self.rot, self.pads)
        closure = np.zeros(self.env.num_envs)
        return self.adapter.actions({self.side: HandCommand(self.pos, self.rot, closure)})


def _turn(pivot: np.ndarray, axis: np.ndarray, angle: np.ndarray, point: np.ndarray,
          ) -> np.ndarray:
    """(N, 3) `point` turned by `angle` (N,) about the axes (N, 3) through `pivot`."""
    return pivot + np.einsum("nij,nj->ni", turned(axis, angle), point - pivot)
