"""Run experts one after another, per env: each hands over when its subgoal holds.

For tasks whose parts can be done in turn and then hold (a drawer stays open while the
hand goes on to lift a ball). The next expert is reset at the hand-over, so it starts
from wherever the hand is.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.base import Expert, host_ids
from dexbench.tasks.plans import SequencePlan


class SequenceExpert:
    """The steps of a `SequencePlan`, each run by the expert `build(env, step.plan)`."""

    def __init__(self, env: DexEnv, plan: SequencePlan,
                 build: Callable[[DexEnv, object], Expert]) -> None:
        self.env, self.plan = env, plan
        self.experts: Sequence[Expert] = [build(env, step.plan) for step in plan.steps]
        self.stage = np.zeros(env.num_envs, dtype=np.int64)
        self.held = np.zeros(env.num_envs)  # s the current step's subgoal has held

    def _done(self, k: int) -> np.ndarray:
        step, expert = self.plan.steps[k], self.experts[k]
        done = expert.finished if step.until is None else step.until(self.env, expert)
        done = np.asarray(done.cpu() if isinstance(done, torch.Tensor) else done, dtype=bool)
        if step.hold <= 0.0:
            return done
        mine = self.stage == k
        self.held[mine] = np.where(done[mine], self.held[mine] + self.env.control_dt, 0.0)
        return done & (self.held >= step.hold - 1e-9)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        self.stage[ids] = 0
        self.held[ids] = 0.0
        self.experts[0].reset(torch.as_tensor(ids))

    def act(self) -> torch.Tensor:
        if self.plan.restart is not None:
            again = (self.stage > 0) & np.asarray(self.plan.restart(self.env, self.experts))
            if again.any():
                self.stage[again] = 0
                self.held[again] = 0.0
                self.experts[0].reset(torch.as_tensor(np.flatnonzero(again)))
        for k in range(len(self.experts) - 1):
            handover = (self.stage == k) & self._done(k)
            if handover.any():
                self.stage[handover] = k + 1
                self.held[handover] = 0.0
                self.experts[k + 1].reset(torch.as_tensor(np.flatnonzero(handover)))
        actions = None
        for k, expert in enumerate(self.experts):
            mine = self.stage == k
            if not mine.any():
                continue
            proposal = expert.act()
            actions = proposal if actions is None else actions
            rows = torch.as_tensor(mine, device=proposal.device)
            actions[rows] = proposal[rows]
        return actions
