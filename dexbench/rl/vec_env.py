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
at the time limit, which RSL-RL bootstraps (`time_outs`); with `starts`, a share of those
resets continue from expert demonstration frames (`dexbench.rl.demo_starts`). Per-iteration
success and reward go to `curve` (success vs wall time), counting only the episodes that
began at the task's own reset.
"""

from __future__ import annotations

import time
from collections.abc import Mapping

import torch
from rsl_rl.env import VecEnv
from tensordict import TensorDict

from dexbench.envs.dex_env import DexEnv
from dexbench.rl.actions import ActionMap
from dexbench.rl.demo_starts import DemoStarts
from dexbench.rl.rewards import RewardTerms

ACTOR_GROUPS = ("policy", "proprio", "contact", "state", "goal")
CRITIC_EXTRA = ("privileged",)


def actor_groups(env: DexEnv) -> tuple[str, ...]:
    """The state groups this task populates, in the actor's (fixed) order."""
    return tuple(g for g in ACTOR_GROUPS if g in env.obs_shapes())


class Curve:
    """Success rate and mean reward of the episodes finished in each iteration.

    Counts accumulate on the env's device and are read once per iteration (reading them
    every step would make the CPU wait for the GPU each step).
    """

    def __init__(self, device: torch.device | str = "cpu") -> None:
        self.start = time.perf_counter()
        self.points: list[dict] = []
        self._sums = torch.zeros(3, dtype=torch.float64, device=device)
        self._steps = 0

    def add(self, done: torch.Tensor, success: torch.Tensor, reward: torch.Tensor) -> None:
        self._sums += torch.stack([done.sum(), (done & success).sum(),
                                   reward.double().mean()]).to(self._sums.dtype)
        self._steps += 1

    def close_iteration(self, env_steps: int) -> dict:
        finished, successes, reward = self._sums.tolist()
        point = {"iteration": len(self.points), "wall_s": time.perf_counter() - self.start,
                 "env_steps": env_steps, "episodes": int(finished),
                 "success_rate": successes / finished if finished else None,
                 "mean_reward": reward / max(self._steps, 1)}
        self.points.append(point)
        self._sums.zero_()
        self._steps = 0
        return point


class RslVecEnv(VecEnv):
    """A `DexEnv` (built with `auto_reset=False` and the actor + critic groups) for RSL-RL."""

    def __init__(self, env: DexEnv, action_map: ActionMap, rewards: Mapping[str, Mapping],
                 steps_per_iteration: int, episode_steps: int | None = None,
                 cfg: dict | None = None, starts: DemoStarts | None = None) -> None:
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
        self.rewards = RewardTerms(env, rewards)
        self._steps_per_iteration = steps_per_iteration
        self._total_steps = 0
        self._prev_action = torch.zeros(env.num_envs, action_map.dim, device=env.device)
        self._solved = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
        self.starts = starts
        self._from_demo = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
        self._obs = env.reset()
        self.curve = Curve(env.device)

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

    @property
    def groups(self) -> dict[str, torch.Tensor]:
        """The latest observation groups, by name (after the resets of the last step)."""
        return self._obs

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
        self.curve.add(done & ~self._from_demo, self._solved, reward)
        self._prev_action = action.clone()
        ids = done.nonzero().flatten()
        final = None
        if len(ids):
            final = self._pack(obs)["actor"][ids]  # what bootstrapping a time-out needs
            self._prev_action[ids] = 0.0
            self._solved[ids] = False
            self._from_demo[ids] = False
            moved = ids[:0] if self.starts is None else self.starts.choose(ids).to(self.device)
            self._from_demo[moved] = True
            obs = env.reset(ids[~self._from_demo[ids]])  # each env reset once, either way
            if len(moved):
                obs = self.starts.start(env, moved)
        self._obs = obs
        self._total_steps += 1
        if self._total_steps % self._steps_per_iteration == 0:
            self.curve.close_iteration(self._total_steps * self.num_envs)
        log = {f"/reward/{k}": v.mean() for k, v in terms.items()}
        log["/sim_warnings"] = info["sim_warnings"].float().mean()
        extras = {"time_outs": done, "log": log, "final_actor": final}
        return self._pack(obs), reward, done.long(), extras
