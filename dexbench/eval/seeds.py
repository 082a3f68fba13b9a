"""Evaluation episode keys, disjoint from every demonstration's by construction.

An episode is fixed by its key (seed, env, episode) (`DexEnv.episode_keys`): reset
sample, goal and variation. Demonstrations (`collect.py`) and plain `env.reset` use keys
(seed, env, k) whose `env` is an env index below the collection's `num_envs`.
Evaluation episode i of a run with seed s is key (s, EVAL_ENV, i), replayed with
`reset_to`: no batched env has 10**9 environments, so no evaluation episode can coincide
with a demonstration of any seed, and episode i is the same whichever env slot runs it
and however many envs there are (which is what makes resuming exact).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

EVAL_ENV = 1_000_000_000


def eval_keys(seed: int, episodes: Sequence[int]) -> np.ndarray:
    """(len(episodes), 3) episode keys of evaluation episodes `episodes` under `seed`."""
    return np.array([(seed, EVAL_ENV, int(i)) for i in episodes], dtype=np.int64).reshape(-1, 3)
