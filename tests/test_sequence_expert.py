"""`SequenceExpert`'s hand-over: a step's subgoal must hold for `Step.hold` seconds."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import torch

from dexbench.experts.sequence import SequenceExpert
from dexbench.tasks.plans import SequencePlan, Step


class _Stub:
    """An expert that proposes its own index as every action."""

    def __init__(self, value: float, n: int) -> None:
        self.value, self.n = value, n

    def reset(self, env_ids: torch.Tensor) -> None:
        del env_ids

    def act(self) -> torch.Tensor:
        return torch.full((self.n, 1), self.value)


def _run(hold: float, shut: list[list[bool]]) -> list[list[float]]:
    """The step index each of 2 envs runs at each act, the first step's `until` reading
    `shut[t]` (per env) at act t."""
    env = SimpleNamespace(num_envs=2, control_dt=0.02, t=0)
    plan = SequencePlan((Step("first", until=lambda e, _: np.array(shut[e.t]), hold=hold),
                         Step("second")))
    expert = SequenceExpert(env, plan, lambda e, p: _Stub(float(p == "second"), 2))
    expert.reset(torch.arange(2))
    out = []
    for t in range(len(shut)):
        env.t = t
        out.append(expert.act()[:, 0].tolist())
    return out


def test_without_hold_the_step_hands_over_the_first_time_its_subgoal_holds():
    steps = _run(0.0, [[False, True], [True, True], [False, False]])
    assert steps == [[0.0, 1.0], [1.0, 1.0], [1.0, 1.0]]


def test_with_hold_the_subgoal_must_hold_that_long_without_a_break():
    # 0.06 s at 0.02 s per act: the third act in a row; env 1's run is broken once.
    shut = [[True, True], [True, False], [True, True], [False, True], [False, True]]
    steps = _run(0.06, shut)
    assert [s[0] for s in steps] == [0.0, 0.0, 1.0, 1.0, 1.0]
    assert [s[1] for s in steps] == [0.0, 0.0, 0.0, 0.0, 1.0]
