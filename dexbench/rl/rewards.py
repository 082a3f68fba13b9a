"""The RL reward: the task's dense reward plus the reference's shaping terms.

The task reward (`Task.reward`) already holds reach (fingertips to the task's focus
point), task progress and the success bonus. On top of it, for lift tasks, a bonus while
the object is off the table and held by at least two fingertips (lift-when-grasping),
and penalties on the squared policy action and its change between steps (action L2 and
rate), which keep the learned motion smooth.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.tasks.templates import LiftTask

GRASP_FORCE = 0.1  # N: a fingertip pushed by the object at least this hard holds it
GRASP_TIPS = 2  # fingertips that must hold the object
LIFT_MIN = 0.01  # m above the reset height


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms (defaults: the DexVerse authors' PPO set-up)."""

    task: float = 1.0
    lift_when_grasping: float = 0.3
    action_l2: float = -0.005
    action_rate: float = -0.005


class RewardTerms:
    """Computes the weighted terms for a batch of transitions of one env."""

    def __init__(self, env: DexEnv, weights: RewardWeights) -> None:
        self.env = env
        self.weights = weights
        task = env.task
        self._lifted = task.lifted if isinstance(task, LiftTask) else None

    def _grasp_lift(self, obs: dict[str, torch.Tensor]) -> torch.Tensor | None:
        """(N,) 1 where the lifted object is off the table and held, else 0."""
        if self._lifted is None or "contact" not in obs:
            return None
        forces = obs["contact"].reshape(self.env.num_envs, -1, 3).norm(dim=-1)
        held = (forces > GRASP_FORCE).sum(dim=1) >= GRASP_TIPS
        lifted = self.env.task.lift(self.env.view, self._lifted) > LIFT_MIN
        return (held & lifted).float()

    def __call__(self, task_reward: torch.Tensor, obs: dict[str, torch.Tensor],
                 action: torch.Tensor, prev_action: torch.Tensor,
                 ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """The total reward (N,) and each weighted term (N,), by name.

        `obs` are the observations right after the step (before any reset), `action`
        and `prev_action` the policy's normalized actions of this and the last step.
        """
        w = self.weights
        terms = {"task": w.task * task_reward.float(),
                 "action_l2": w.action_l2 * action.square().sum(dim=1),
                 "action_rate": w.action_rate * (action - prev_action).square().sum(dim=1)}
        grasp = self._grasp_lift(obs)
        if grasp is not None:
            terms["lift_when_grasping"] = w.lift_when_grasping * grasp
        return torch.stack(list(terms.values())).sum(dim=0), terms
