"""Closed-loop rollouts of one policy on one batched env: each env slot runs evaluation
episodes from a queue until the queue is empty.

A slot's episode ends at the first step where the task's success predicate holds
(`terminated`: a success) or at the time limit (`truncated`: a failure); the slot is
then reset into the next queued episode with `reset_to` and the policy forgets that
slot's history. Slots left without an episode idle until the batch is done.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Sequence

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.eval.records import EpisodeRecord
from dexbench.eval.seeds import eval_keys
from dexbench.eval.video import EpisodeVideos
from dexbench.policies.common.protocol import Policy


def run_episodes(env: DexEnv, policy: Policy, episodes: Sequence[int], seed: int,
                 on_episode: Callable[[EpisodeRecord], None],
                 videos: EpisodeVideos | None = None) -> None:
    """Run evaluation episodes `episodes` (indices) and report each as it ends."""
    queue = deque(episodes)
    n = env.num_envs
    running = np.full(n, -1)  # episode index per slot, -1: idle
    started = np.zeros(n)

    def begin(slots: np.ndarray) -> dict[str, torch.Tensor] | None:
        take = slots[:len(queue)]
        running[slots[len(take):]] = -1
        if not len(take):
            return None
        eps = [queue.popleft() for _ in take]
        running[take] = eps
        obs = env.reset_to(take, eval_keys(seed, eps))
        policy.reset(torch.as_tensor(take))
        started[take] = time.perf_counter()
        if videos is not None:
            for slot, ep in zip(take, eps, strict=True):
                videos.begin(int(slot), ep)
            videos.capture([int(s) for s in take])
        return obs

    reads_next = getattr(policy, "reads_next", lambda: None)
    obs = begin(np.arange(n))
    while (running >= 0).any():
        action = policy.act(obs)
        obs, _, terminated, truncated, info = env.step(action, observe=reads_next())
        if videos is not None:
            videos.capture()
        warnings = info["sim_warnings"].cpu().numpy()  # since each env's reset
        success = terminated.cpu().numpy()
        ended = np.flatnonzero((success | truncated.cpu().numpy()) & (running >= 0))
        steps = info["steps"].cpu().numpy()
        now = time.perf_counter()
        for slot in ended:
            record = EpisodeRecord(
                task=env.task.name, episode=int(running[slot]), seed=seed,
                success=bool(success[slot]), steps=int(steps[slot]),
                time_s=round(now - started[slot], 4), sim_warnings=int(warnings[slot]),
                embodiment=env.embodiment.name)
            if videos is not None:
                videos.end(int(slot), record.success)
            on_episode(record)
        if len(ended):
            fresh = begin(ended)
            obs = obs if fresh is None else fresh
