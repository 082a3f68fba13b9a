"""The training curve: success of finished episodes vs wall-clock time, as a PNG."""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")  # files only: no display on servers

import matplotlib.pyplot as plt

SMOOTH = 10  # iterations pooled per plotted point


def pooled(points: list[dict]) -> tuple[list[float], list[float]]:
    """(minutes, success) per iteration with finished episodes, success pooled over the
    last `SMOOTH` iterations (one iteration finishes few episodes: its rate is noise)."""
    xs, ys = [], []
    for i in range(len(points)):
        window = points[max(0, i - SMOOTH + 1): i + 1]
        episodes = sum(p["episodes"] for p in window)
        if episodes:
            wins = sum(p["success_rate"] * p["episodes"] for p in window if p["episodes"])
            xs.append(points[i]["wall_s"] / 60.0)
            ys.append(wins / episodes)
    return xs, ys


def plot_curve(points: list[dict], path: pathlib.Path, title: str) -> None:
    """Success rate (episodes pooled over `SMOOTH` iterations) against minutes."""
    plot_runs([("", points)], path, title)


def plot_runs(runs: list[tuple[str, list[dict]]], path: pathlib.Path, title: str) -> None:
    """Several runs' pooled success against minutes on one plot (labels in a legend)."""
    fig, ax = plt.subplots(figsize=(5.0, 3.2), dpi=150)
    for label, points in runs:
        xs, ys = pooled(points)
        ax.plot(xs, ys, label=label or None,
                color="#2f5d8a" if len(runs) == 1 else None,
                marker="." if len(xs) < 30 else None)
    ax.set_xlabel("wall time (min)")
    ax.set_ylabel("success rate (finished episodes)")
    ax.set_ylim(-0.02, 1.02)
    ax.set_title(title, fontsize=8)
    ax.grid(alpha=0.3)
    if any(label for label, _ in runs):
        ax.legend(fontsize=7)
    fig.tight_layout()
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    tmp.replace(path)


def milestones(points: list[dict], minutes: tuple[float, ...],
               target: float) -> dict:
    """Pooled success at the last iteration before each of `minutes` (None past the
    run's end, half a minute of slack), and the first minute at which it reached
    `target` (None: never)."""
    xs, ys = pooled(points)
    pairs = list(zip(xs, ys, strict=True))
    at = {m: next((y for x, y in reversed(pairs) if x <= m), None)
          if xs and m <= xs[-1] + 0.5 else None for m in minutes}
    first = next((x for x, y in pairs if y >= target), None)
    return {"at": at, "first_at_target_min": first,
            "final": ys[-1] if ys else None, "minutes": xs[-1] if xs else 0.0}
