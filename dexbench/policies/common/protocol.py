"""The interface between a trained (or scripted) policy and the closed-loop evaluator.

A policy is built for one batched `DexEnv` and returns one action per env per control
step; action chunking, re-planning and observation history live inside the policy, so
the evaluator only loops `act` -> `env.step` and calls `reset` on finished envs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import torch


@dataclass(frozen=True)
class PolicySpec:
    """What a policy needs from the env it is run in, read before the env is built.

    `obs` is the observation preset (or group list) to build the env with; `task` and
    `embodiment` are those it was trained on (None: any); `action_layout` the ordered
    actuator names its actions follow (None: any), checked against the env's; `cameras`
    the cameras its image groups come from (None: those the env config names); `history`
    the env-side frame stack it wants (None: the preset's; 0 for a policy that keeps its
    own window, so that the env may skip frames it will not read).
    """

    obs: str | tuple[str, ...]
    task: str | None = None
    embodiment: str | None = None
    action_layout: tuple[str, ...] | None = None
    cameras: tuple[str, ...] | None = None
    history: int | None = None


class Policy(Protocol):
    """A batched closed-loop policy over one `DexEnv`."""

    spec: PolicySpec

    def reset(self, env_ids: torch.Tensor) -> None:
        """Forget history and queued actions of those envs (called after they reset)."""

    def act(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        """Absolute joint targets (num_envs, action_dim) for the current observations.

        A policy may also define `reads_next() -> Tensor | None`, called after `act`: the
        envs whose next observation it will read (bool, (num_envs,)); the evaluator then
        renders camera groups only for those (`DexEnv.step(observe=)`).
        """


class ActionLayoutError(ValueError):
    """A checkpoint was trained for a different action layout than the env's."""


def check_action_layout(spec: PolicySpec, actuators: tuple[str, ...] | list[str]) -> None:
    """Refuse to drive an env whose actuators differ from those the policy was trained on."""
    if spec.action_layout is None or tuple(spec.action_layout) == tuple(actuators):
        return
    trained, env = list(spec.action_layout), list(actuators)
    first = next((i for i, (a, b) in enumerate(zip(trained, env, strict=False)) if a != b),
                 min(len(trained), len(env)))
    raise ActionLayoutError(
        f"the checkpoint was trained for {len(trained)} actuators "
        f"(embodiment {spec.embodiment!r}) but the env has {len(env)}; they first differ at "
        f"index {first}. Evaluate it with embodiment={spec.embodiment} or retrain.")
