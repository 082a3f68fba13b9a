"""Turn a part about a vertical axis by regrasping it: grasp, turn the wrist, let go,
turn back, grasp again (a nut run down a bolt, a stiff knob).

The grasp is the hand's own `grasp_offset` palm-down over the part's point, so the
script serves every hand; the turn is about the vertical through that point, so the
held part turns in place. The point is read every step: a nut going down its thread
takes the hand down with it.
"""

from __future__ import annotations

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import ActionAdapter, HandCommand, site_pose
from dexbench.experts.base import host_ids
from dexbench.experts.motion import palm_down, step_towards, turned
from dexbench.tasks.plans import TwistPlan, locate

SPEED = 0.5  # m/s in the air
HOVER = 0.025  # m above the grasp pose between strokes
CLOSE_SECONDS = 0.25  # the fingers close ...
OPEN_SECONDS = 0.3  # ... and open this long
ARRIVED = 0.006  # m from a waypoint: there
UP = np.array([0.0, 0.0, 1.0])


class TwistExpert:
    """Phases per env: 0 over the part, 1 down onto it, 2 closing, 3 turning, 4 opening,
    5 rising; then 0 again."""

    def __init__(self, env: DexEnv, plan: TwistPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self.body, self.point = locate(env.task.objects, plan.obj, plan.point)
        self.offset = np.asarray(env.embodiment.hand.grasp_offset) + np.asarray(plan.shift)
        self._palm = env.scene.model.site(env.embodiment.sides[side].palm_site).id
        n = env.num_envs
        self.pos = np.zeros((n, 3))
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.phase = np.zeros(n, dtype=np.int64)
        self.timer = np.zeros(n)
        self.angle = np.zeros(n)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot = site_pose(self.env, self._palm)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.phase[ids], self.timer[ids], self.angle[ids] = 0, 0.0, 0.0
        self.adapter.reset(ids)

    def act(self) -> torch.Tensor:
        dt = self.env.control_dt
        point = self.env.view.point_pos(self.body, self.point).cpu().numpy()
        n = self.env.num_envs
        turning = self.phase == 3
        self.angle = np.where(turning, np.maximum(self.angle - self.plan.turn_rate * dt,
                                                  self.plan.stroke)
                              if self.plan.stroke < 0 else
                              np.minimum(self.angle + self.plan.turn_rate * dt, self.plan.stroke),
                              np.where(self.phase >= 4, self.angle, 0.0))
        rot = turned(np.repeat(UP[None], n, axis=0), self.angle) @ palm_down(
            np.full(n, self.plan.yaw))
        grasp = point - np.einsum("nij,j->ni", rot, self.offset)
        above = grasp + HOVER * UP
        aim = np.where(((self.phase == 0) | (self.phase == 5))[:, None], above, grasp)
        self.timer += dt
        there = np.linalg.norm(self.pos - aim, axis=1) < ARRIVED
        done = ((self.phase == 0) & there) | ((self.phase == 1) & there) | (
            (self.phase == 2) & (self.timer > CLOSE_SECONDS)) | (
            turning & (self.angle == self.plan.stroke)) | (
            (self.phase == 4) & (self.timer > OPEN_SECONDS)) | ((self.phase == 5) & there)
        self.phase = np.where(done, (self.phase + 1) % 6, self.phase)
        self.timer[done] = 0.0
        closure = np.select([self.phase == 2, self.phase == 3, self.phase == 4],
                            [np.minimum(1.0, self.timer / CLOSE_SECONDS), 1.0,
                             np.maximum(0.0, 1.0 - self.timer / OPEN_SECONDS)], 0.0)
        self.pos, self.rot = step_towards(self.pos, self.rot, aim, rot, SPEED * dt,
                                          2 * self.plan.turn_rate * dt)
        command = HandCommand(self.pos, self.rot, closure, self.plan.synergy)
        return self.adapter.actions({self.side: command})
