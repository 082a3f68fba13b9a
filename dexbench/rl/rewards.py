"""The RL reward: a weighted sum of named terms, listed in `conf/rl_rewards/<preset>.yaml`.

A term is a function of one transition and of its own parameters, returning (N,) values,
or None where it does not apply to the task (a lift bonus on a task with nothing to
lift). A preset lists terms as `name: {weight: w, <param>: value}`; `default` is the
DexVerse authors' PPO set-up: the task's dense reward (reach, progress and the success
bonus, `Task.reward`), a bonus while the lifted object is off the table and held by at
least two fingertips, and penalties on the squared action and its change between steps,
which keep the learned motion smooth. `rl_rewards=<preset>` picks another preset,
`rl.rewards.<term>.weight=...` changes a weight, `+rl.rewards.success.weight=5` adds a
term and `~rl.rewards.<term>` drops one.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import torch

from dexbench.envs.dex_env import DexEnv


@dataclass(frozen=True)
class Transition:
    """One batched step as the terms see it: `obs` right after the step (before any
    reset), `action` and `prev_action` the policy's normalized actions."""

    env: DexEnv
    task_reward: torch.Tensor
    obs: dict[str, torch.Tensor]
    action: torch.Tensor
    prev_action: torch.Tensor


def task(t: Transition) -> torch.Tensor:
    """The task's own dense reward."""
    return t.task_reward.float()


def success(t: Transition) -> torch.Tensor:
    """1 while the task's success condition holds."""
    return t.env.task.success(t.env.view).float()


def action_l2(t: Transition) -> torch.Tensor:
    return t.action.square().sum(dim=1)


def action_rate(t: Transition) -> torch.Tensor:
    return (t.action - t.prev_action).square().sum(dim=1)


def lifted_body(env: DexEnv, body: str = "auto") -> str | None:
    """`body`, or with `auto` the object the task lifts (None if it lifts nothing)."""
    return getattr(env.task, "lifted", None) if body == "auto" else body


def holding(env: DexEnv, obs: dict[str, torch.Tensor], force: float, tips: int) -> torch.Tensor:
    """(N,) whether at least `tips` fingertips push with `force` N or more (`contact`)."""
    forces = obs["contact"].reshape(env.num_envs, -1, 3).norm(dim=-1)
    return (forces > force).sum(dim=1) >= tips


def lift_when_grasping(t: Transition, body: str = "auto", force: float = 0.1, tips: int = 2,
                       min_lift: float = 0.01) -> torch.Tensor | None:
    """1 where `body` (auto: the object the task lifts, if any) is `min_lift` m above its
    reset height and at least `tips` fingertips push on it with `force` N or more."""
    name = lifted_body(t.env, body)
    if name is None or "contact" not in t.obs:
        return None
    held = holding(t.env, t.obs, force, tips)
    return (held & (t.env.task.lift(t.env.view, name) > min_lift)).float()


TERMS: dict[str, Callable[..., torch.Tensor | None]] = {
    f.__name__: f for f in (task, success, action_l2, action_rate, lift_when_grasping)}


def check_terms(terms: Mapping[str, Mapping[str, Any]]) -> None:
    """A clear error for an unknown term, a missing weight or an unknown parameter."""
    for name, spec in terms.items():
        if name not in TERMS:
            raise ValueError(f"unknown reward term {name!r}; terms: {', '.join(TERMS)}")
        if spec is None or "weight" not in spec:
            raise ValueError(f"reward term {name!r} needs a weight (rl.rewards.{name}.weight)")
        params = set(inspect.signature(TERMS[name]).parameters) - {"t"}
        unknown = set(spec) - params - {"weight"}
        if unknown:
            raise ValueError(f"reward term {name!r} has no parameter {sorted(unknown)}; "
                             f"parameters: {sorted(params) or 'none'}")


class RewardTerms:
    """The weighted terms of `terms` (a preset's mapping) for batches of one env."""

    def __init__(self, env: DexEnv, terms: Mapping[str, Mapping[str, Any]]) -> None:
        check_terms(terms)
        self.env = env
        self._terms = [(name, float(spec["weight"]), TERMS[name],
                        {k: v for k, v in spec.items() if k != "weight"})
                       for name, spec in terms.items()]

    def __call__(self, task_reward: torch.Tensor, obs: dict[str, torch.Tensor],
                 action: torch.Tensor, prev_action: torch.Tensor,
                 ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """The total reward (N,) and each weighted term that applies (N,), by name."""
        t = Transition(self.env, task_reward, obs, action, prev_action)
        out = {}
        for name, weight, fn, params in self._terms:
            value = fn(t, **params)
            if value is not None:
                out[name] = weight * value
        total = torch.stack(list(out.values())).sum(dim=0) if out else torch.zeros_like(
            task_reward, dtype=torch.float32)
        return total, out
