"""Success rates with 95% Wilson score intervals, per task, per category and overall.

Wilson's interval stays inside [0, 1] and keeps a sensible width at 0/50 or 50/50,
where the normal approximation collapses to a point.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass

from dexbench.eval.records import EpisodeRecord

Z95 = 1.959963984540054  # two-sided 95% normal quantile


def wilson_interval(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion `successes / n`."""
    if n <= 0 or not 0 <= successes <= n:
        raise ValueError(f"need 0 <= successes <= n and n > 0, got {successes}/{n}")
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z / denom * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    # Rounding can put a bound a hair inside p itself (p = 1, n = 10: 0.99999...): the
    # interval always holds the observed rate.
    return max(0.0, min(p, centre - half)), min(1.0, max(p, centre + half))


@dataclass(frozen=True)
class TaskResult:
    task: str
    category: str
    episodes: int
    successes: int
    success_rate: float
    ci_low: float
    ci_high: float
    mean_steps: float
    mean_episode_s: float  # wall time of an episode, averaged (batched episodes overlap)


def task_result(task: str, category: str, records: Iterable[EpisodeRecord]) -> TaskResult:
    records = list(records)
    n = len(records)
    k = sum(r.success for r in records)
    low, high = wilson_interval(k, n)
    return TaskResult(task, category, n, k, k / n, low, high,
                      sum(r.steps for r in records) / n, sum(r.time_s for r in records) / n)


def summarize(groups: dict[str, list[str]], records: Iterable[EpisodeRecord],
              skipped: dict[str, str], info: dict) -> dict:
    """Per-task results, per-category means (unweighted over the category's evaluated
    tasks, as the paper reports) and the overall mean over tasks, as one JSON object.

    `groups` orders categories and their tasks; tasks without episodes are left out of
    the means and listed under `skipped` when a reason is given, else `pending`.
    """
    by_task: dict[str, list[EpisodeRecord]] = {}
    for r in records:
        by_task.setdefault(r.task, []).append(r)
    tasks, categories, pending = [], [], []
    for category, names in groups.items():
        done = [task_result(t, category, by_task[t]) for t in names if t in by_task]
        pending += [t for t in names if t not in by_task and t not in skipped]
        tasks += done
        if done:
            categories.append({"category": category, "tasks": [r.task for r in done],
                               "mean": _mean(r.success_rate for r in done)})
    return {
        **info,
        "tasks": [asdict(r) for r in tasks],
        "categories": categories,
        "overall": _mean(r.success_rate for r in tasks) if tasks else None,
        "episodes": sum(r.episodes for r in tasks),
        "skipped": [{"task": t, "reason": why} for t, why in skipped.items()],
        "pending": pending,
    }


def _mean(values: Iterable[float]) -> float:
    values = list(values)
    return sum(values) / len(values)
