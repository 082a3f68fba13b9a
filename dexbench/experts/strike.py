"""Strike: hold a tool, bring its face over a point (a nail head) and press it down there,
again and again, until the task says the job is done.

`GraspExpert` grasps the tool and carries its face to a hover point above the target; a
press then commands the palm straight down, a fixed `depth` past the hover height plus
the gap, so the force on the target is the wrist's stiffness times that overshoot, not a
run-away push. The face never leaves the tool's own contact: the hand stays on the grip.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.base import host_ids
from dexbench.experts.grasp import GraspExpert
from dexbench.tasks.plans import StrikePlan, locate

ARRIVED = 0.008  # m: the face this close to its hover point starts a press
# A press that drove the target less than `SLOW` (m) makes the next one `DEEPER` (m), up
# to `MOST` past the hover height plus the gap: a softer mount (a long arm's wrist is
# less stiff than the floating wrist it was tuned on) presses harder for the same drive.
SLOW, DEEPER, MOST = 0.005, 0.01, 0.06
# The hover point rises `CONE` m per m the face is still off to the side of the aim, so
# the face comes down onto the target from above: a lagging arm that let the carry sink
# as it closed in brought the hand level with the nail head beside it, and touching the
# nail fails the task.
CONE = 1.0


class StrikeExpert:
    """Hover over the target, press, rise, press again until `plan.done`."""

    def __init__(self, env: DexEnv, plan: StrikePlan, side: str = "right") -> None:
        self.env, self.plan = env, plan
        self.face = locate(env.task.objects, plan.grasp.obj, plan.face)
        self.aim = locate(env.task.objects, plan.on, plan.at)
        grasp = dataclasses.replace(plan.grasp, target=self._target, goal_point=plan.face)
        self.grasp = GraspExpert(env, grasp, side)
        n = env.num_envs
        self.pressing = np.zeros(n, dtype=bool)
        self.timer = np.zeros(n)
        self.bottom = np.zeros((n, 3))  # where the palm is commanded during a press
        self.depth = np.full(n, plan.depth)  # m the next press goes past the target
        self.top = np.zeros(n)  # the target's height when the press began
        # the face and the aim this step, read once in `act` for it and `_target`
        self._now = self._points()

    def _points(self) -> tuple[np.ndarray, np.ndarray]:
        view = self.env.view
        return view.point_pos(*self.face).cpu().numpy(), view.point_pos(*self.aim).cpu().numpy()

    def _target(self, env: DexEnv) -> np.ndarray:
        """Where the face goes: above the aim, or, pressing, wherever puts the palm
        command at `bottom` (the carry moves the palm by the face's error)."""
        face, aim = self._now
        hover = aim + [0.0, 0.0, self.plan.hover]
        off = np.linalg.norm((face - aim)[:, :2], axis=1)
        hover[:, 2] += CONE * np.maximum(off - ARRIVED, 0.0)
        press = face + self.bottom - self.grasp.pos
        return np.where(self.pressing[:, None], press, hover)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        self.pressing[ids], self.timer[ids] = False, 0.0
        self.depth[ids] = self.plan.depth
        self.grasp.reset(env_ids)

    def act(self) -> torch.Tensor:
        face, aim = self._now = self._points()
        carrying = self.grasp.carrying
        done = np.asarray(self.plan.done(self.env))
        above = np.linalg.norm(face - aim - [0.0, 0.0, self.plan.hover], axis=1) < ARRIVED
        start = carrying & above & ~self.pressing & ~done
        self.bottom[start] = self.grasp.pos[start]
        self.bottom[start, 2] -= self.plan.hover + self.depth[start]
        self.top[start] = aim[start, 2]
        self.pressing |= start
        self.timer = np.where(self.pressing, self.timer + self.env.control_dt, 0.0)
        was = self.pressing.copy()
        self.pressing &= carrying & (self.timer < self.plan.press) & ~done
        slow = was & ~self.pressing & (self.top - aim[:, 2] < SLOW)
        self.depth[slow] = np.minimum(self.depth[slow] + DEEPER, MOST)
        return self.grasp.act()

    @property
    def finished(self) -> np.ndarray:
        return np.asarray(self.plan.done(self.env)) & ~self.pressing
