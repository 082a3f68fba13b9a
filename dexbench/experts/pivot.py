"""Pivot a flat object up about its far edge, held by a support, by lifting its near edge.

For a board lying flat with its far end at a wall (PivotLargeCuboidAgainstWall), or any
flat object a support keeps from sliding away: the open hand turns with the object, its
fingers down the near end face, their tips leaning towards the pivot and the pads facing
it, so that lifting loads the fingers along their length, where they are stiff (hanging
straight down, the weak fingers fold back and slide up the face instead). Every step the
fingertips (their mean, thumb left out) are commanded to the cradle point just outside
the near edge, led `PRESS` towards the pivot (the support takes the push) and `LEAD`
along the arc the edge moves on, from where the fingertips are: friction on the end face
carries it round. The fingertips never go below the table. A hand that has lost the edge
goes back over it and comes down again; once `done`, it holds still.
"""

from __future__ import annotations

from enum import IntEnum

import numpy as np
import torch

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import (
    ActionAdapter,
    HandCommand,
    palm_and_finger_sites,
    tips_in_palm_frame,
)
from dexbench.experts.base import host_ids
from dexbench.experts.motion import step_towards
from dexbench.tasks.plans import PivotPlan, locate


class Phase(IntEnum):
    ABOVE = 0  # over the point behind the near edge
    DOWN = 1  # down behind it
    LIFT = 2  # lifting it round the pivot
    HOLD = 3  # done: holding still


SPEED = 0.4  # m/s in the air
LIFT_SPEED = 0.08  # m/s of the fingertips while lifting
TURN_RATE = 3.0  # rad/s
TIP_RADIUS = 0.011  # m: the cradle point's distance out from the edge, both ways
FLOOR = 0.006  # m: the fingertip sites stay this far above the table
STANDOFF = 0.03  # m behind the edge before coming in
HIGH = 0.10  # m above the edge when travelling over it
PRESS = 0.03  # m the command leads the fingertips towards the pivot
LEAD = 0.03  # m the command leads them along the arc
ARRIVED = 0.008  # m
LOST = 0.06  # m from the near edge: the fingertips have lost it
LEAN = 0.4  # rad the fingertips lean ahead: they, not the fingers' backs, meet the end
ENGAGED = 0.004  # m: fingertips this close to the end face (or past it) press on it


class PivotExpert:
    """The pivoting hand of a single-hand env (or one side of a bimanual one)."""

    def __init__(self, env: DexEnv, plan: PivotPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self._palm, self._tips = palm_and_finger_sites(env, side)
        self.end = locate(env.task.objects, plan.obj, plan.end)
        self.pivot = locate(env.task.objects, plan.obj, plan.pivot)
        n = env.num_envs
        self.phase = np.zeros(n, dtype=np.int64)
        self.contact = np.zeros((n, 3))  # the fingertips' mean in the palm frame
        self.pos = np.zeros((n, 3))  # commanded fingertip mean
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        palm, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.contact[ids] = tips[ids].mean(axis=1)
        self.rot[ids] = rot[ids]
        self.pos[ids] = palm[ids] + np.einsum("nij,nj->ni", rot[ids], self.contact[ids])
        self.phase[ids] = Phase.ABOVE
        self.adapter.reset(ids)

    def _tips_now(self) -> np.ndarray:
        palm, rot, _ = tips_in_palm_frame(self.env, self._palm, self._tips)
        return palm + np.einsum("nij,nj->ni", rot, self.contact)

    def act(self) -> torch.Tensor:
        view = self.env.view
        end = view.point_pos(*self.end).cpu().numpy()
        pivot = view.point_pos(*self.pivot).cpu().numpy()
        a = pivot - end
        a /= np.linalg.norm(a, axis=1, keepdims=True)  # along the object, towards the pivot
        u = a.copy()
        u[:, 2] = 0.0
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        n = np.cross(np.cross(a, [0.0, 0.0, 1.0]), a)  # the object's up, square to `a`
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        cradle = end - TIP_RADIUS * (a + n) / np.sqrt(2.0)
        cradle[:, 2] = np.maximum(cradle[:, 2], TABLE_TOP_Z + FLOOR)
        hang = _hanging(a, n)
        tip = self._tips_now()
        phase = self.phase
        lost = np.linalg.norm(tip - end, axis=1) > LOST
        phase[(phase >= Phase.LIFT) & (phase < Phase.HOLD) & lost] = Phase.ABOVE
        done = np.asarray(self.plan.done(self.env), dtype=bool)
        phase[done & (phase >= Phase.LIFT)] = Phase.HOLD
        target = cradle - STANDOFF * u
        above = phase == Phase.ABOVE
        target[above, 2] = end[above, 2] + HIGH
        lift = phase == Phase.LIFT
        # Only fingertips pressing on the end face lead it up (ones on their way in would
        # rise before they touch it), and from where they are: a finger's lowest point,
        # not its site, rests on the table, so from the cradle point they would not pull.
        engaged = ((tip - cradle) * a).sum(axis=1) > -ENGAGED
        above_cradle = np.maximum(((tip - cradle) * n).sum(axis=1), 0.0)
        rise = engaged * (above_cradle + LEAD)
        target[lift] = (cradle + PRESS * a + rise[:, None] * n)[lift]
        hold = phase == Phase.HOLD
        target[hold] = self.pos[hold]
        hang[hold] = self.rot[hold]
        speed = np.where(phase >= Phase.LIFT, LIFT_SPEED, SPEED)[:, None] * self.env.control_dt
        self.pos, self.rot = step_towards(self.pos, self.rot, target, hang, speed,
                                          TURN_RATE * self.env.control_dt)
        arrived = np.linalg.norm(self.pos - target, axis=1) < ARRIVED
        turned = np.einsum("nij,nij->n", self.rot, hang) > 3.0 - 1e-3
        phase[above & arrived & turned] = Phase.DOWN
        phase[(phase == Phase.DOWN) & arrived & ~above] = Phase.LIFT
        palm_cmd = self.pos - np.einsum("nij,nj->ni", self.rot, self.contact)
        closure = np.zeros(len(end))
        return self.adapter.actions({self.side: HandCommand(palm_cmd, self.rot, closure)})


def _hanging(a: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(N, 3, 3) hand frames that turn with the object (along `a`, up `n`, (N, 3)): the
    fingers down its end face, their tips leaning `LEAN` towards the pivot, the palm
    facing the pivot (tilted up as much). Lifting the end then loads the fingers along
    their length, where they are stiff, whatever the tilt."""
    fingers = np.sin(LEAN) * a - np.cos(LEAN) * n
    palm = np.cos(LEAN) * a + np.sin(LEAN) * n
    return np.stack([fingers, np.cross(palm, fingers), palm], axis=2)
