"""Insert a held peg into a hole: line its axis up with the bore, then push it home.

The grasp comes first (`GraspExpert`, lifting the peg a little); this expert takes over
the closed hand. Every step it reads where the peg actually is in the hand (head point
and shaft axis), turns the hand by the rotation that takes the shaft onto the bore axis
and moves it so the head goes first in front of the entrance, then into the bore. The
peg is held across its shaft near the grip, so turning the hand about the vertical does
not make it pivot between the fingers.
"""

from __future__ import annotations

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import ActionAdapter, HandCommand, site_pose
from dexbench.experts.base import host_ids
from dexbench.experts.grasp import squeezed
from dexbench.experts.motion import step_towards, turned
from dexbench.tasks.plans import InsertPlan

SPEED = 0.15  # m/s while lining up
PUSH_SPEED = 0.04  # m/s into the bore
TURN_RATE = 1.0  # rad/s
STANDOFF = 0.03  # m in front of the entrance where the head lines up
LINED_UP = 0.0025  # m of head offset from the line-up point ...
ALIGNED = np.radians(2.5)  # ... and shaft angle from the bore axis, before pushing
JAMMED = np.radians(8.0)  # shaft angle while pushing: back out and line up again ...
STUCK_SECONDS = 1.5  # ... as when the head is not past the entrance after this long
ENTERED = 0.005  # m past the entrance: the head is in the bore
STALL_SECONDS = 4.0  # lining up this long without pushing: `stalled` (grasp it again)
PUSH_PAST = 0.01  # m the push aims beyond the target (the bottom stops it)
KEYED = np.radians(4.0)  # keyed fits: the key's misalignment before pushing


class InsertExpert:
    """Line up, then push in; the hand stays closed on the peg throughout."""

    def __init__(self, env: DexEnv, plan: InsertPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self.pose = squeezed(self.adapter, env, plan.synergy, plan.squeeze)
        peg, hole = env.task.objects[plan.peg], env.task.objects[plan.hole]
        self.head, self.shaft = peg.points[plan.head], peg.axes[plan.shaft]
        self.entrance, self.target = hole.points[plan.entrance], hole.points[plan.target]
        self.bore = hole.axes[plan.bore]
        self.key = None if plan.key is None else (peg.axes[plan.key[0]], hole.axes[plan.key[1]],
                                                  plan.key[2])
        self._palm = env.scene.model.site(env.embodiment.sides[side].palm_site).id
        n = env.num_envs
        self.pos = np.zeros((n, 3))
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.pushing = np.zeros(n, dtype=bool)
        self.push_time = np.zeros(n)
        self.line_up_time = np.zeros(n)

    @property
    def stalled(self) -> np.ndarray:
        """(N,) envs lining up for `STALL_SECONDS` without getting to push (a peg that
        turned in the hand, a hand that cannot reach): worth a new grasp."""
        return self.line_up_time > STALL_SECONDS

    def _palm_pose(self) -> tuple[np.ndarray, np.ndarray]:
        return site_pose(self.env, self._palm)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot = self._palm_pose()
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.pushing[ids] = False
        self.push_time[ids] = 0.0
        self.line_up_time[ids] = 0.0
        self.adapter.reset(ids)

    def act(self) -> torch.Tensor:
        view = self.env.view
        head = view.point_pos(*self.head).cpu().numpy()
        shaft = view.axis(*self.shaft).cpu().numpy()
        inward = -view.axis(*self.bore).cpu().numpy()
        entrance = view.point_pos(*self.entrance).cpu().numpy()
        line_up = entrance - (STANDOFF * inward)
        home = view.point_pos(*self.target).cpu().numpy() + PUSH_PAST * inward
        angle = np.arccos(np.clip((shaft * inward).sum(axis=1), -1.0, 1.0))
        # The turn taking the shaft onto the bore axis, about the palm.
        axis = np.cross(shaft, inward)
        norm = np.linalg.norm(axis, axis=1, keepdims=True)
        axis = np.where(norm > 1e-9, axis / np.maximum(norm, 1e-9), [0.0, 0.0, 1.0])
        turn = turned(axis, angle)
        keyed = np.ones(self.env.num_envs, dtype=bool)
        if self.key is not None:
            peg_key, hole_key, period = self.key
            peg_key = np.einsum("nij,nj->ni", turn, view.axis(*peg_key).cpu().numpy())
            hole_key = view.axis(*hole_key).cpu().numpy()
            # Then about the bore, by the least turn matching the keys (modulo the period).
            spin = np.arctan2((np.cross(peg_key, hole_key) * inward).sum(axis=1),
                              (peg_key * hole_key).sum(axis=1))
            spin = (spin + period / 2) % period - period / 2
            turn = turned(inward, spin) @ turn
            keyed = np.abs(spin) < KEYED
        self.pushing |= ((np.linalg.norm(head - line_up, axis=1) < LINED_UP)
                         & (angle < ALIGNED) & keyed)
        self.push_time = np.where(self.pushing, self.push_time + self.env.control_dt, 0.0)
        outside = ((head - entrance) * inward).sum(axis=1) < ENTERED
        self.pushing &= (angle < JAMMED) & ~(outside & (self.push_time > STUCK_SECONDS))
        self.line_up_time = np.where(self.pushing, 0.0, self.line_up_time + self.env.control_dt)
        goal = np.where(self.pushing[:, None], home, line_up)
        palm, palm_rot = self._palm_pose()
        target_pos = goal - np.einsum("nij,nj->ni", turn, head - palm)
        target_rot = turn @ palm_rot
        speed = np.where(self.pushing, PUSH_SPEED, SPEED)[:, None] * self.env.control_dt
        self.pos, self.rot = step_towards(self.pos, self.rot, target_pos, target_rot, speed,
                                          TURN_RATE * self.env.control_dt)
        closure = np.ones(self.env.num_envs)
        command = HandCommand(self.pos, self.rot, closure, self.pose)
        return self.adapter.actions({self.side: command})
