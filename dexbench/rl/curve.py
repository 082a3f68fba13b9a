"""The training curve: success of finished episodes vs wall-clock time, as a PNG."""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")  # files only: no display on servers

import matplotlib.pyplot as plt

SMOOTH = 10  # iterations pooled per plotted point


def plot_curve(points: list[dict], path: pathlib.Path, title: str) -> None:
    """Success rate (episodes pooled over `SMOOTH` iterations) against minutes."""
    xs, ys = [], []
    for i in range(len(points)):
        window = points[max(0, i - SMOOTH + 1): i + 1]
        episodes = sum(p["episodes"] for p in window)
        if episodes:
            wins = sum(p["success_rate"] * p["episodes"] for p in window if p["episodes"])
            xs.append(points[i]["wall_s"] / 60.0)
            ys.append(wins / episodes)
    fig, ax = plt.subplots(figsize=(5.0, 3.2), dpi=150)
    ax.plot(xs, ys, color="#2f5d8a", marker="." if len(xs) < 30 else None)
    ax.set_xlabel("wall time (min)")
    ax.set_ylabel("success rate (finished episodes)")
    ax.set_ylim(-0.02, 1.02)
    ax.set_title(title, fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    tmp = path.with_name(f".{path.stem}.tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    tmp.replace(path)
