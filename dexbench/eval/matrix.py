"""The cross-embodiment matrix: every (task, embodiment) cell of a split, as tables, a
heatmap and the acceptance numbers, rebuilt from the matrix folder alone.

A matrix folder (`runs/matrix/<split>/`) holds `matrix.json` (the identity and the task
order) and one evaluation run folder per cell, `<task>/<embodiment>/` (`eval.py`'s
files: `results.json` is read here), with the cell's `feasibility.json`
(`dexbench/eval/feasibility.py`). Single-hand tasks pair with the single-hand
embodiments, two-hand tasks with the bimanual ones: two panels. Infeasible cells are
still evaluated; they are hatched and kept out of every mean and acceptance count, as
are cells not evaluated yet.
"""

from __future__ import annotations

import csv
import io
import json
import pathlib
from collections.abc import Iterable
from dataclasses import asdict, dataclass

import matplotlib

matplotlib.use("Agg")  # files only: no display on servers

import matplotlib.pyplot as plt
from matplotlib.patches import Rectangle

from dexbench.embodiments.builder import embodiment_names, parse_embodiment
from dexbench.eval.feasibility import pose_limited, verdict
from dexbench.eval.merge import RESULTS_FILE
from dexbench.eval.tables import write_text

MATRIX_FILE = "matrix.json"
FEASIBILITY_FILE = "feasibility.json"
PNG_FILE, CSV_FILE, MD_FILE, SUMMARY_FILE = "matrix.png", "matrix.csv", "matrix.md", "summary.json"
BAR = 0.5  # a cell "works" at this expert success rate
CELL_TARGET = 0.7  # the target share of feasible cells at BAR
PANELS = (("single-hand", False), ("bimanual", True))


def pairs(tasks: Iterable[tuple[str, bool]], embodiments: Iterable[str] | None = None
          ) -> list[tuple[str, str]]:
    """Every (task, embodiment) cell: a task (name, bimanual) with every embodiment of
    its arity, in registry order; `embodiments` (names) narrows the columns."""
    names = embodiment_names() if embodiments is None else list(embodiments)
    arity = {name: parse_embodiment(name).bimanual for name in names}
    order = {name: i for i, name in enumerate(embodiment_names())}
    names = sorted(names, key=order.__getitem__)
    return [(task, e) for task, bimanual in tasks for e in names if arity[e] == bimanual]


def cell_dir(root: pathlib.Path, task: str, embodiment: str) -> pathlib.Path:
    return root / task / embodiment


def cell_complete(folder: pathlib.Path, episodes: int) -> bool:
    """Whether a cell's evaluation holds all `episodes` (a finished run's results)."""
    path = folder / RESULTS_FILE
    if not path.exists():
        return False
    summary = json.loads(path.read_text())
    return bool(summary.get("complete")) and summary.get("episodes_per_task") == episodes


@dataclass(frozen=True)
class Cell:
    """One (task, embodiment) result; `rate` None while nothing is evaluated."""

    task: str
    embodiment: str
    bimanual: bool
    episodes: int = 0
    successes: int = 0
    rate: float | None = None
    ci_low: float | None = None
    ci_high: float | None = None
    complete: bool = False
    feasible: bool = True
    reason: str = "not measured"
    pose_limited: bool = False  # reachable, but not in the plan's orientations

    @property
    def counted(self) -> bool:
        """Whether the cell enters means and acceptance: evaluated and feasible."""
        return self.rate is not None and self.feasible


def read_cell(root: pathlib.Path, task: str, embodiment: str) -> Cell:
    """A cell as its folder holds it."""
    folder = cell_dir(root, task, embodiment)
    bimanual = parse_embodiment(embodiment).bimanual
    measurement = None
    if (folder / FEASIBILITY_FILE).exists():
        measurement = json.loads((folder / FEASIBILITY_FILE).read_text())
    feasible, reason = verdict(measurement)
    limited = pose_limited(measurement)
    base = Cell(task, embodiment, bimanual, feasible=feasible, reason=reason,
                pose_limited=limited)
    if not (folder / RESULTS_FILE).exists():
        return base
    summary = json.loads((folder / RESULTS_FILE).read_text())
    rows = [t for t in summary["tasks"] if t["task"] == task]
    if not rows:
        return base
    row = rows[0]
    return Cell(task, embodiment, bimanual, row["episodes"], row["successes"],
                row["success_rate"], row["ci_low"], row["ci_high"],
                bool(summary.get("complete")), feasible, reason, limited)


def read_matrix(root: pathlib.Path) -> tuple[dict, list[Cell]]:
    """`matrix.json` and every cell of its tasks found in the folder, in task order and
    registry order of embodiments."""
    info = json.loads((root / MATRIX_FILE).read_text())
    order = {name: i for i, name in enumerate(embodiment_names())}
    cells = []
    for task in info["tasks"]:
        task_folder = root / task["task"]
        if not task_folder.is_dir():
            continue
        names = sorted((p.name for p in task_folder.iterdir()
                        if p.is_dir() and p.name in order), key=order.__getitem__)
        cells += [read_cell(root, task["task"], name) for name in names]
    return info, cells


def _mean(values: list[float]) -> float | None:
    return sum(values) / len(values) if values else None


def _share_ok(rates: list[float]) -> bool:
    """At BAR on at least half of them."""
    return bool(rates) and 2 * sum(r >= BAR for r in rates) >= len(rates)


def build(cells: list[Cell], tasks: list[str]) -> dict:
    """Panels (rows, columns, means) and the acceptance numbers, as `summary.json`."""
    panels = []
    for title, bimanual in PANELS:
        mine = [c for c in cells if c.bimanual == bimanual]
        rows = [t for t in tasks if any(c.task == t for c in mine)]
        cols = list(dict.fromkeys(c.embodiment for c in mine))
        order = {name: i for i, name in enumerate(embodiment_names())}
        cols.sort(key=order.__getitem__)
        if not rows:
            continue
        counted = [c for c in mine if c.counted]
        panels.append({
            "title": title, "tasks": rows, "embodiments": cols,
            "task_means": {t: _mean([c.rate for c in counted if c.task == t]) for t in rows},
            "embodiment_means": {e: _mean([c.rate for c in counted if c.embodiment == e])
                                 for e in cols},
            "mean": _mean([c.rate for c in counted])})
    counted = [c for c in cells if c.counted]
    by_emb: dict[str, list[float]] = {}
    by_task: dict[str, list[float]] = {}
    for c in counted:
        by_emb.setdefault(c.embodiment, []).append(c.rate)
        by_task.setdefault(c.task, []).append(c.rate)
    emb_failing = sorted((e for e, r in by_emb.items() if not _share_ok(r)),
                         key=embodiment_names().index)
    task_failing = [t for t in tasks if t in by_task and not _share_ok(by_task[t])]
    at_bar = sum(c.rate >= BAR for c in counted)
    share = at_bar / len(counted) if counted else None
    return {
        "bar": BAR,
        "cells": len(cells),
        "evaluated": sum(c.rate is not None for c in cells),
        "complete": sum(c.complete for c in cells),
        "feasible_evaluated": len(counted),
        "feasible_at_bar": at_bar,
        "share_feasible_at_bar": share,
        "embodiments": len(by_emb),
        "embodiments_ok": len(by_emb) - len(emb_failing),
        "embodiments_failing": emb_failing,
        "tasks": len(by_task),
        "tasks_ok": len(by_task) - len(task_failing),
        "tasks_failing": task_failing,
        "accepted": {"cells": share is not None and share >= CELL_TARGET,
                     "embodiments": bool(by_emb) and not emb_failing,
                     "tasks": bool(by_task) and not task_failing},
        "mean": _mean([c.rate for c in counted]),
        "panels": panels,
        "infeasible": [{"task": c.task, "embodiment": c.embodiment, "rate": c.rate,
                        "reason": c.reason} for c in cells if not c.feasible],
        # a cell called infeasible that the expert solves anyway: the test to look at
        "infeasible_at_bar": [f"{c.task} x {c.embodiment}" for c in cells
                              if not c.feasible and c.rate is not None and c.rate >= BAR],
        # feasible, but the plan's poses are beyond the arm's wrist: for plan fixes
        "pose_limited": [f"{c.task} x {c.embodiment}" for c in cells
                         if c.feasible and c.pose_limited],
        "pending": [{"task": c.task, "embodiment": c.embodiment, "episodes": c.episodes}
                    for c in cells if not c.complete],
        "results": [asdict(c) for c in cells],
    }


def _rate(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def _cells_by_key(cells: list[Cell]) -> dict[tuple[str, str], Cell]:
    return {(c.task, c.embodiment): c for c in cells}


def markdown(info: dict, summary: dict, cells: list[Cell]) -> str:
    """One table per panel (tasks x embodiments with margin means), the acceptance
    numbers and the infeasible cells with their reasons."""
    by_key = _cells_by_key(cells)
    lines = [f"Expert success on split {info['split']}: {info['episodes']} episodes per "
             f"cell. `(x)`: infeasible (hatched in the heatmap; kept out of the means), "
             "`-`: not evaluated, `x*`: unfinished.", ""]
    for panel in summary["panels"]:
        cols = panel["embodiments"]
        lines += [f"**{panel['title']}**", "",
                  "| task | " + " | ".join(cols) + " | mean |",
                  "|---|" + "---:|" * (len(cols) + 1)]
        for task in panel["tasks"]:
            row = []
            for emb in cols:
                cell = by_key.get((task, emb))
                text = _rate(None if cell is None else cell.rate)
                if cell is not None and cell.rate is not None and not cell.complete:
                    text += "*"
                if cell is not None and not cell.feasible:
                    text = f"({text})"
                row.append(text)
            lines.append(f"| {task} | " + " | ".join(row)
                         + f" | **{_rate(panel['task_means'][task])}** |")
        lines.append("| **mean** | " + " | ".join(
            f"**{_rate(panel['embodiment_means'][e])}**" for e in cols)
            + f" | **{_rate(panel['mean'])}** |")
        lines.append("")
    lines += acceptance_lines(summary)
    if summary["infeasible"]:
        lines += ["", "Infeasible cells:", ""]
        lines += [f"- {c['task']} x {c['embodiment']} ({_rate(c['rate'])}): {c['reason']}"
                  for c in summary["infeasible"]]
    return "\n".join(lines) + "\n"


def acceptance_lines(summary: dict) -> list[str]:
    """The issue's three acceptance numbers, one line each."""
    share = summary["share_feasible_at_bar"]
    mark = {True: "met", False: "not met"}
    acc = summary["accepted"]
    lines = [
        f"- feasible cells at >= {BAR}: {summary['feasible_at_bar']}/"
        f"{summary['feasible_evaluated']} = {_rate(share)} (target {CELL_TARGET}: "
        f"{mark[acc['cells']]})",
        f"- embodiments at >= {BAR} on at least half of their tasks: "
        f"{summary['embodiments_ok']}/{summary['embodiments']} ({mark[acc['embodiments']]})"
        + (f"; not: {', '.join(summary['embodiments_failing'])}"
           if summary["embodiments_failing"] else ""),
        f"- tasks at >= {BAR} on at least half of their embodiments: "
        f"{summary['tasks_ok']}/{summary['tasks']} ({mark[acc['tasks']]})"
        + (f"; not: {', '.join(summary['tasks_failing'])}" if summary["tasks_failing"]
           else ""),
    ]
    if summary["pose_limited"]:
        lines.append(f"- feasible, but the arm cannot take the plan's own poses (wrist "
                     f"limits; see feasibility.json): {', '.join(summary['pose_limited'])}")
    if summary["infeasible_at_bar"]:
        lines.append(f"- marked infeasible yet at >= {BAR}: "
                     f"{', '.join(summary['infeasible_at_bar'])}")
    if summary["pending"]:
        lines.append(f"- unfinished cells: {len(summary['pending'])} of {summary['cells']}")
    return lines


CSV_COLUMNS = ("row", "task", "embodiment", "episodes", "successes", "success_rate",
               "ci_low", "ci_high", "complete", "feasible", "pose_limited", "reason")


def csv_text(summary: dict, cells: list[Cell]) -> str:
    """One row per cell, then the per-task, per-embodiment and overall means."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)

    def num(value: float | None) -> str:
        return "" if value is None else f"{value:.4f}"

    for c in cells:
        writer.writerow(["cell", c.task, c.embodiment, c.episodes, c.successes, num(c.rate),
                         num(c.ci_low), num(c.ci_high), int(c.complete), int(c.feasible),
                         int(c.pose_limited), c.reason])
    for panel in summary["panels"]:
        for task, mean in panel["task_means"].items():
            writer.writerow(["task mean", task, "", "", "", num(mean), *[""] * 6])
        for emb, mean in panel["embodiment_means"].items():
            writer.writerow(["embodiment mean", "", emb, "", "", num(mean), *[""] * 6])
        writer.writerow([f"{panel['title']} mean", "", "", "", "", num(panel["mean"]),
                         *[""] * 6])
    writer.writerow(["mean", "", "", "", "", num(summary["mean"]), *[""] * 6])
    return out.getvalue()


def _short(embodiment: str) -> str:
    return embodiment.removeprefix("bimanual_")


CELL_IN = 0.42  # inches per heatmap cell


def heatmap(info: dict, summary: dict, cells: list[Cell], path: pathlib.Path) -> None:
    """Panels of tasks (rows) x embodiments (columns): success coloured and written in
    each cell, infeasible cells hatched, a margin column of task means and a margin row
    of embodiment means (PNG via a temp file and a rename)."""
    panels = summary["panels"]
    by_key = _cells_by_key(cells)
    cmap = plt.get_cmap("RdYlGn")
    ncols = max((len(p["embodiments"]) for p in panels), default=1)
    # Inches: a cell is as tall as it is wide (0.42 in), and each panel adds room for
    # its title and its 90-degree embodiment labels, however few its rows.
    heights = [CELL_IN * (len(p["tasks"]) + 1.3) + 1.5 for p in panels] or [1.0]
    fig, axes = plt.subplots(len(heights), 1, squeeze=False, dpi=150,
                             figsize=(max(4.5, 2.6 + CELL_IN * (ncols + 1.3)),
                                      sum(heights) + 0.6),
                             gridspec_kw={"height_ratios": heights})
    gap = 0.3

    def square(ax: plt.Axes, x: float, y: float, rate: float | None, hatch: bool,
               bold: bool = False, star: bool = False) -> None:
        face = "#e0e0e0" if rate is None else cmap(rate)
        ax.add_patch(Rectangle((x, y), 1, 1, facecolor=face, edgecolor="white", lw=0.6))
        if hatch:
            ax.add_patch(Rectangle((x, y), 1, 1, fill=False, hatch="////",
                                   edgecolor="#333333", lw=0))
        text = _rate(rate) + ("*" if star and rate is not None else "")
        dark = rate is not None and not 0.2 < rate < 0.85 and not hatch
        ax.text(x + 0.5, y + 0.5, text, ha="center", va="center", fontsize=5.2,
                weight="bold" if bold else "normal", color="white" if dark else "#111111",
                bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.6}
                if hatch else None)

    for ax, panel in zip(axes[:, 0], panels, strict=False):
        rows, cols = panel["tasks"], panel["embodiments"]
        for i, task in enumerate(rows):
            for j, emb in enumerate(cols):
                cell = by_key.get((task, emb))
                rate = None if cell is None else cell.rate
                square(ax, j, i, rate, cell is not None and not cell.feasible,
                       star=cell is not None and not cell.complete)
            square(ax, len(cols) + gap, i, panel["task_means"][task], False, bold=True)
        for j, emb in enumerate(cols):
            square(ax, j, len(rows) + gap, panel["embodiment_means"][emb], False, bold=True)
        square(ax, len(cols) + gap, len(rows) + gap, panel["mean"], False, bold=True)
        ax.set_xlim(0, len(cols) + gap + 1)
        ax.set_ylim(len(rows) + gap + 1, 0)
        ax.set_xticks([j + 0.5 for j in range(len(cols))] + [len(cols) + gap + 0.5],
                      [_short(e) for e in cols] + ["mean"], rotation=90, fontsize=6)
        ax.set_yticks([i + 0.5 for i in range(len(rows))] + [len(rows) + gap + 0.5],
                      rows + ["mean"], fontsize=6)
        ax.tick_params(length=0)
        for side in ax.spines.values():
            side.set_visible(False)
        ax.set_aspect("equal")
        kind = ("bimanual embodiments (bimanual_ left out)" if panel["title"] == "bimanual"
                else "single-hand embodiments")
        ax.set_title(f"{panel['title']} tasks on {kind}", fontsize=7)
    head = (f"Expert success on {info['split']}, {info['episodes']} episodes per cell\n"
            "hatched: infeasible (kept out of the means); *: unfinished")
    fig.suptitle(head, fontsize=8)
    fig.tight_layout()
    tmp = path.with_name(f".{path.name}.tmp")
    fig.savefig(tmp, format="png")
    plt.close(fig)
    tmp.replace(path)


def write_outputs(root: pathlib.Path, plot: bool = True) -> dict:
    """matrix.{md,csv,png} and summary.json of the matrix folder `root`; the summary."""
    info, cells = read_matrix(root)
    summary = build(cells, [t["task"] for t in info["tasks"]])
    summary = {"split": info["split"], "episodes_per_cell": info["episodes"], **summary}
    write_text(root / MD_FILE, markdown(info, summary, cells))
    write_text(root / CSV_FILE, csv_text(summary, cells))
    write_text(root / SUMMARY_FILE, json.dumps(summary, indent=2) + "\n")
    if plot and summary["panels"]:
        heatmap(info, summary, cells, root / PNG_FILE)
    return summary


def rate_line(cell: Cell) -> str:
    """`0.75 (15/20, 95% CI [0.53, 0.89])`, and the verdict when infeasible."""
    if cell.rate is None:
        return "no episodes"
    text = (f"{cell.rate:.2f} ({cell.successes}/{cell.episodes}, 95% CI "
            f"[{cell.ci_low:.2f}, {cell.ci_high:.2f}])")
    return text if cell.feasible else f"{text}; infeasible: {cell.reason}"
