"""Either hand: a push-and-hold plan run by whichever hand of a pair reaches it better.

A bimanual task whose object may lie anywhere across the table (OpenFlatFolder's folder
at y in +-0.2 m) has one hand push a part along its joint while the other holds or
waits. A fixed pushing hand had to reach across for an object on the other hand's side:
the FR3's right arm, lifting a folder's flap up and over at y = +0.18 m, stretched its
elbow nearly straight; its IK gave up the palm's frame for its position (17 deg off), the
pads slid off the flap at 51% of its travel, and the task needs 60% (11 of 20 episodes
failed so, with every hand on the FR3). So a plan whose `side` is `EITHER` is built once
per hand, and at each reset every episode takes the one whose mount misses the push's
palm poses (`HoldActuateExpert.push_poses`) least (`ActionAdapter.reach_cost`), the
right hand first among those within `REACH_MARGIN` of the best: floating hands reach
alike, so they keep the right one.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import nearly_best
from dexbench.experts.base import Expert, host_ids
from dexbench.experts.hold_actuate import HoldActuateExpert
from dexbench.tasks.plans import HoldActuatePlan

ORDER = ("right", "left")  # the hand that pushes where both reach alike comes first


class EitherHandExpert:
    """Runs `plan` with each env's better-reaching pushing hand (one
    `HoldActuateExpert` per hand, each holding with the other)."""

    def __init__(self, env: DexEnv, plan: HoldActuatePlan,
                 build: Callable[[object, str], Expert]) -> None:
        self.env = env
        sides = [s for s in ORDER if s in env.embodiment.sides]
        self.experts = [HoldActuateExpert(env, dataclasses.replace(plan, side=s), build)
                        for s in sides]
        self.chosen = np.zeros(env.num_envs, dtype=np.int64)  # index into `experts`
        self._floating = env.embodiment.mount == "floating"

    def reset(self, env_ids: torch.Tensor) -> None:
        for expert in self.experts:
            expert.reset(env_ids)
        ids = host_ids(env_ids)
        self.chosen[ids] = 0
        if self._floating or len(self.experts) < 2:
            return
        paths = [expert.push_poses() for expert in self.experts]
        for i in ids:
            costs = [e.adapter.reach_cost(e.plan.side, i, [(p[i], r[i]) for p, r in path])
                     for e, path in zip(self.experts, paths, strict=True)]
            self.chosen[i] = nearly_best(costs)

    @property
    def finished(self) -> np.ndarray:
        done = [np.asarray(e.finished) for e in self.experts]
        return np.choose(self.chosen, done)

    def act(self) -> torch.Tensor:
        actions = None
        for k, expert in enumerate(self.experts):
            if not (self.chosen == k).any():
                continue  # its state goes stale where unused; a reset renews it
            out = expert.act()
            rows = torch.as_tensor(self.chosen == k, device=out.device)
            actions = out if actions is None else torch.where(rows[:, None], out, actions)
        return actions
