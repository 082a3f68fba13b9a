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

Subgoal = Callable[[DexEnv], torch.Tensor]


class SequenceExpert:
    """`steps`: (expert, subgoal) pairs; the last subgoal is never consulted. Where
    `restart(env)` holds (e.g. a held object was dropped), an env starts over."""

    def __init__(self, env: DexEnv, steps: Sequence[tuple[Expert, Subgoal]],
                 restart: Subgoal | None = None) -> None:
        self.env, self.steps, self.restart = env, list(steps), restart
        self.stage = np.zeros(env.num_envs, dtype=np.int64)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        self.stage[ids] = 0
        self.steps[0][0].reset(torch.as_tensor(ids))

    def act(self) -> torch.Tensor:
        if self.restart is not None:
            again = (self.stage > 0) & self.restart(self.env).cpu().numpy()
            if again.any():
                self.stage[again] = 0
                self.steps[0][0].reset(torch.as_tensor(np.flatnonzero(again)))
        for k, (_, done) in enumerate(self.steps[:-1]):
            handover = (self.stage == k) & done(self.env).cpu().numpy()
            if handover.any():
                self.stage[handover] = k + 1
                self.steps[k + 1][0].reset(torch.as_tensor(np.flatnonzero(handover)))
        actions = None
        for k, (expert, _) in enumerate(self.steps):
            mine = self.stage == k
            if not mine.any():
                continue
            proposal = expert.act()
            actions = proposal if actions is None else actions
            actions[torch.as_tensor(mine, device=proposal.device)] = proposal[
                torch.as_tensor(mine, device=proposal.device)]
        return actions
