"""Bar chart of success by category: one bar per category mean, its tasks as dots with
their 95% Wilson intervals, the overall mean as a dashed line."""

from __future__ import annotations

import pathlib
import textwrap

import matplotlib

matplotlib.use("Agg")  # files only: no display on servers

import matplotlib.pyplot as plt


def _save(fig: plt.Figure, ax: plt.Axes, path: pathlib.Path) -> None:
    """The legend, then the PNG: a temp file renamed, so no reader sees half a chart."""
    ax.legend(fontsize=7, loc="upper left", ncol=3, frameon=False)
    fig.tight_layout()
    tmp = path.with_name(f".{path.name}.tmp")
    fig.savefig(tmp, format="png")
    plt.close(fig)
    tmp.replace(path)


def category_chart(summary: dict, path: pathlib.Path) -> None:
    """Write the chart as PNG (temp file, then rename)."""
    cats = summary["categories"]
    fig, ax = plt.subplots(figsize=(max(4.0, 1.2 * len(cats) + 1.5), 3.6), dpi=150)
    xs = range(len(cats))
    ax.bar(xs, [c["mean"] for c in cats], color="#8fb3d9", edgecolor="#2f5d8a", width=0.6,
           label="category mean")
    by_task = {t["task"]: t for t in summary["tasks"]}
    label = "task (95% CI)"
    for x, cat in zip(xs, cats, strict=True):
        tasks = [by_task[t] for t in cat["tasks"]]
        offsets = [0.0] if len(tasks) == 1 else [
            -0.2 + 0.4 * i / (len(tasks) - 1) for i in range(len(tasks))]
        for dx, t in zip(offsets, tasks, strict=True):
            rate = t["success_rate"]
            ax.errorbar(x + dx, rate, yerr=[[rate - t["ci_low"]], [t["ci_high"] - rate]],
                        fmt="o", color="#1b1b1b", markersize=3, capsize=2, linewidth=0.8,
                        label=label)
            label = None
    if summary["overall"] is not None:
        ax.axhline(summary["overall"], color="#c0392b", linestyle="--", linewidth=1,
                   label=f"overall {summary['overall']:.2f}")
    ax.set_xticks(list(xs), [c["category"] for c in cats], rotation=30, ha="right")
    ax.set_xlim(-0.7, len(cats) - 0.3)
    ax.set_ylim(0, 1.18)
    ax.set_ylabel("success rate")
    head = textwrap.shorten(f"{summary['policy_label']} on {summary['label']}", width=70,
                            placeholder="...")
    ax.set_title(f"{head}\n{summary['episodes_per_task']} episodes per task, 95% Wilson "
                 "intervals", fontsize=8)
    _save(fig, ax, path)


def merged_chart(categories: list[tuple[str, list[str]]],
                 means: dict[str, dict[str, float | None]], path: pathlib.Path) -> None:
    """Grouped bars of a merged table: per category (and overall) one bar per policy
    column, so that measured and published columns compare at a glance (PNG, temp file,
    then rename)."""
    groups = [c for c, _ in categories] + ["all"]
    policies = list(means["all"])
    width = 0.8 / max(1, len(policies))
    fig, ax = plt.subplots(figsize=(max(5.0, 0.3 * len(groups) * len(policies) + 1.5), 3.4),
                           dpi=150)
    colors = plt.get_cmap("tab10")
    for i, policy in enumerate(policies):
        xs = [g + (i - (len(policies) - 1) / 2) * width for g in range(len(groups))]
        ys = [means[c][policy] or 0.0 for c in groups]
        ax.bar(xs, ys, width=width * 0.95, color=colors(i % 10), label=policy,
               hatch="//" if policy.endswith("(paper)") else None, edgecolor="white")
    ax.set_xticks(range(len(groups)), groups, rotation=20, ha="right")
    ax.set_ylim(0, 1.1)
    ax.set_ylabel("mean success rate")
    _save(fig, ax, path)
