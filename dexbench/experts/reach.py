"""Reach: move the open hand to a point (keeping its orientation, or turned palm-down with
its finger tips there), e.g. to tip an object over, back out of a machine or wait above
a lever. Finished once the command has arrived."""

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
from dexbench.experts.motion import palm_down, pitch_down, step_towards
from dexbench.tasks.plans import ReachPlan

SPEED = 0.3  # m/s of the open hand moving on its own
TURN_RATE = 2.0  # rad/s
ARRIVED = 0.01  # m


class ReachExpert:
    """Straight to `plan.target(env, start)` at `plan.speed` (default `SPEED`), hand
    open."""

    def __init__(self, env: DexEnv, plan: ReachPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self._palm, self._tips = palm_and_finger_sites(env, side)
        n = env.num_envs
        self.pos, self.start = np.zeros((n, 3)), np.zeros((n, 3))
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.tips = np.zeros((n, 3))  # finger tips in the hand frame

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.tips[ids] = tips[ids].mean(axis=1)
        self.start[ids] = self.pos[ids]
        self.adapter.reset(ids)

    def _goal(self) -> tuple[np.ndarray, np.ndarray]:
        target = self.plan.target(self.env, self.start)
        if self.plan.yaw is None:
            return target, self.rot
        rot = palm_down(np.full(self.env.num_envs, self.plan.yaw)) @ pitch_down(self.plan.pitch)
        return target - np.einsum("nij,nj->ni", rot, self.tips), rot

    @property
    def finished(self) -> np.ndarray:
        return np.linalg.norm(self.pos - self._goal()[0], axis=1) < ARRIVED

    def act(self) -> torch.Tensor:
        pos, rot = self._goal()
        speed = SPEED if self.plan.speed is None else self.plan.speed
        self.pos, self.rot = step_towards(self.pos, self.rot, pos, rot,
                                          speed * self.env.control_dt,
                                          TURN_RATE * self.env.control_dt)
        command = HandCommand(self.pos, self.rot, np.zeros(self.env.num_envs))
        return self.adapter.actions({self.side: command})
