"""`policy=expert`: the task's scripted expert run closed-loop as a policy.

It reads privileged simulator state from the env itself (not the observations), so it
is an upper reference for learned policies and a check of the evaluator; it has no
checkpoint.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts import make_expert
from dexbench.policies.common.protocol import PolicySpec


def spec(checkpoint: str | None, options: Mapping[str, Any]) -> PolicySpec:
    if checkpoint is not None:
        raise ValueError(f"policy=expert takes no checkpoint (got {checkpoint!r})")
    return PolicySpec(obs="state")


class ExpertPolicy:
    """Adapts a scripted `Expert` to the `Policy` protocol (observations unused)."""

    def __init__(self, env: DexEnv) -> None:
        self.spec = PolicySpec(obs="state", task=env.task.name,
                               action_layout=tuple(env.embodiment.actuators))
        self._expert = make_expert(env)

    def reset(self, env_ids: torch.Tensor) -> None:
        self._expert.reset(env_ids)

    def act(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        return self._expert.act()


def build(checkpoint: str | None, env: DexEnv, device: torch.device | str,
          options: Mapping[str, Any]) -> ExpertPolicy:
    spec(checkpoint, options)
    return ExpertPolicy(env)
