"""RSL-RL's `VecEnv` over a batched `DexEnv`.

Actions become joint targets through an `ActionMap` (`dexbench.rl.actions`: per-joint
deltas, or mount deltas plus synergy weights per hand), from the targets applied last
(the env's `policy` observation group, the home pose after a reset).
The actor sees the state observation groups, the critic those plus `privileged`.
Training episodes last `episode_steps` control steps and do not end at success: ending
them there would make success cost the positive reward of every later step, so PPO would
learn to hover just short of it; the policy instead learns to reach success and hold it.
An episode counts as solved when the env's success (the condition held for
`SUCCESS_HOLD_STEPS`) occurred in it, as in the evaluator. Environments reset inside `step`
at the time limit, which RSL-RL bootstraps (`time_outs`). Per-iteration success and reward
go to `curve` (success vs wall time).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from dexbench.envs.dex_env import DexEnv
from dexbench.rl.actions import ActionMap
from dexbench.rl.rewards import RewardTerms, RewardWeights

ACTOR_GROUPS = ("policy", "proprio", "contact", "state", "goal")
CRITIC_EXTRA = ("privileged",)


def actor_groups(env: DexEnv) -> tuple[str, ...]:
    """The state groups this task populates, in the actor's (fixed) order."""
    return tuple(g for g in ACTOR_GROUPS if g in env.obs_shapes())


@dataclass
class Curve:
    """Success rate and mean reward of the episodes finished in each iteration."""

    start: float = field(default_factory=time.perf_counter)
    points: list[dict] = field(default_factory=list)
    _finished: int = 0
    _successes: int = 0
    _reward: float = 0.0
    _steps: int = 0

    def add(self, done: torch.Tensor, success: torch.Tensor, reward: torch.Tensor) -> None:
        self._finished += int(done.sum())
        self._successes += int((done & success).sum())
        self._reward += float(reward.mean())
        self._steps += 1

    def close_iteration(self, env_steps: int) -> dict:
        point = {"iteration": len(self.points), "wall_s": time.perf_counter() - self.start,
                 "env_steps": env_steps, "episodes": self._finished,
                 "success_rate": self._successes / self._finished if self._finished else None,
                 "mean_reward": self._reward / max(self._steps, 1)}
        self.points.append(point)
        self._finished = self._successes = self._steps = 0
        self._reward = 0.0
        return point


class RslVecEnv(VecEnv):
    """A `DexEnv` (built with `auto_reset=False` and the actor + critic groups) for RSL-RL."""

    def __init__(self, env: DexEnv, action_map: ActionMap, weights: RewardWeights,
                 steps_per_iteration: int, episode_steps: int | None = None,
                 cfg: dict | None = None) -> None:
        if env.auto_reset:
            raise ValueError("build the env with auto_reset=False: RslVecEnv resets it")
        self.env = env
        self.num_envs = env.num_envs
        self.action_map = action_map
        self.num_actions = action_map.dim
        self.max_episode_length = episode_steps or env.episode_steps
        if not 0 < self.max_episode_length <= env.episode_steps:
            raise ValueError(f"episode_steps must be in 1..{env.episode_steps} (the task's "
                             f"time limit), got {episode_steps}")
        self.device = env.device
        self.cfg = cfg or {}
        self.actor_groups = actor_groups(env)
        have = env.obs_shapes()
        self.critic_groups = self.actor_groups + tuple(g for g in CRITIC_EXTRA if g in have)
        self.rewards = RewardTerms(env, weights)
        self._steps_per_iteration = steps_per_iteration
        self._total_steps = 0
        self._prev_action = torch.zeros(env.num_envs, action_map.dim, device=env.device)
        self._solved = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
        self._obs = env.reset()
        self.curve = Curve()

    @property
    def episode_length_buf(self) -> torch.Tensor:
        return self.env.steps

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        """RSL-RL spreads the first time-outs by starting episodes at random lengths."""
        self.env.steps[:] = value.to(self.env.steps)

    def _pack(self, obs: dict[str, torch.Tensor]) -> TensorDict:
        actor = torch.cat([obs[g] for g in self.actor_groups], dim=1)
        critic = torch.cat([obs[g] for g in self.critic_groups], dim=1)
        return TensorDict({"actor": actor, "critic": critic}, batch_size=[self.num_envs],
                          device=self.device)

    def get_observations(self) -> TensorDict:
        return self._pack(self._obs)

    def step(self, actions: torch.Tensor) -> tuple[TensorDict, torch.Tensor, torch.Tensor,
                                                   dict]:
        env = self.env
        action = actions.to(self.device).clamp(-1.0, 1.0)
        targets = self.action_map.targets(env.last_action, action)
        obs, task_reward, terminated, _, info = env.step(targets)
        reward, terms = self.rewards(task_reward, obs, action, self._prev_action)
        self._solved |= terminated
        done = env.steps >= self.max_episode_length
        self.curve.add(done, self._solved, reward)
        self._prev_action = action.clone()
        ids = done.nonzero().flatten()
        if len(ids):
            obs = env.reset(ids)
            self._prev_action[ids] = 0.0
            self._solved[ids] = False
        self._obs = obs
        self._total_steps += 1
        if self._total_steps % self._steps_per_iteration == 0:
            self.curve.close_iteration(self._total_steps * self.num_envs)
        log = {f"/reward/{k}": v.mean() for k, v in terms.items()}
        log["/sim_warnings"] = info["sim_warnings"].float().mean()
        extras = {"time_outs": done, "log": log}
        return self._pack(obs), reward, done.long(), extras
