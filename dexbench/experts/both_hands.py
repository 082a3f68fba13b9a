"""Both hands at once, each on its own plan: two doors, two drawers, one per hand.

Each hand's script runs as it would alone (built for its side); its actions for that
hand's actuators are kept, the other hand's columns come from the other script.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.base import Expert
from dexbench.tasks.plans import BothHandsPlan


class BothHandsExpert:
    """The hands' scripts of a `BothHandsPlan` (`build(plan, side)` makes each), run side
    by side."""

    def __init__(self, env: DexEnv, plan: BothHandsPlan,
                 build: Callable[[object, str], Expert]) -> None:
        self.env, self.plan = env, plan
        self.experts = {side: build(p, side) for side, p in plan.hands.items()}
        self._cols = {side: env.embodiment.side_actuators(side) for side in plan.hands}

    def reset(self, env_ids: torch.Tensor) -> None:
        for expert in self.experts.values():
            expert.reset(env_ids)

    @property
    def finished(self) -> np.ndarray:
        done = [np.asarray(e.finished) for e in self.experts.values()]
        return np.logical_and.reduce(done)

    def act(self) -> torch.Tensor:
        actions = None
        for side, expert in self.experts.items():
            proposal = expert.act()
            if actions is None:
                actions = proposal
            else:
                actions[:, self._cols[side]] = proposal[:, self._cols[side]]
        return actions
