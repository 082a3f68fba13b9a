"""The tool-use experts away from the floating Shadow hand: each case failed on its
first evaluation episode before, for the reason in its id.

- fr3_shadow pour: the pour turn drove the Shadow forearm into the FR3's link 5; the
  contact held joint 7 short and the mug tipped 30 degrees, not 100. The arm's IK now
  keeps its links clear of the hand's mount part (`ActionAdapter._mount_part`).
- floating_sharpa pour: a firm grip holds the mug at the hand's own turn, 91 degrees;
  the turn now goes on until the mug is tipped (`PourPlan.tip`).
- fr3_shadow hammer: the lifted head swung the Shadow wrist, and the arm chasing each
  swing flung the hammer out (`GraspPlan.commanded_hand`).
"""

from __future__ import annotations

import pytest
import torch

from dexbench.eval.seeds import eval_keys
from dexbench.experts import make_expert
from dexbench.tasks.registry import make_env


@pytest.mark.parametrize(("task", "embodiment", "steps"), [
    ("FunctionalPourMug", "fr3_shadow", 560),
    ("FunctionalPourMug", "floating_sharpa", 560),
    ("FunctionalHammerStrike", "fr3_shadow", 800),
], ids=["arm-takes-the-pour-turn", "firm-grip-tips-the-mug", "arm-keeps-the-hammer"])
def test_expert_solves_episode_0(task: str, embodiment: str, steps: int) -> None:
    env = make_env(task, embodiment, num_envs=1, seed=0, nthread=1)
    env.reset_to(torch.arange(1), eval_keys(0, [0]))
    expert = make_expert(env)
    expert.reset(torch.arange(1))
    for _ in range(steps):
        env.step(expert.act())
        if env.task.success(env.view)[0]:
            break
    assert env.task.success(env.view)[0]
