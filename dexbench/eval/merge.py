"""The paper-style table from several evaluation runs: tasks x policies, grouped by
category with a mean row per category and overall, the best value of each row in bold.

A folder without `results.json` stands for every run below it (a `-m` sweep's folder).
Runs of one policy label on disjoint tasks (a split swept one task per job) share one
column; runs of one label that overlap get a column each, named by their folders.
Published columns (a `Reference`, e.g. the paper's table) can stand beside them, on the
tasks the runs evaluated."""

from __future__ import annotations

import csv
import io
import json
import pathlib
from dataclasses import dataclass, field

from dexbench.eval.plot import merged_chart
from dexbench.eval.tables import tex_escape, write_text

RESULTS_FILE = "results.json"


class MergeError(ValueError):
    """Runs that cannot be merged (missing results, nothing in common)."""


@dataclass(frozen=True)
class Reference:
    """Published success rates to set beside ours (`conf/reference/<name>.yaml`)."""
    source: str
    columns: list[str]
    tasks: dict[str, list[float]]  # task -> one rate per column

    def label(self, column: str) -> str:
        return f"{column} (paper)"


@dataclass(frozen=True)
class MergedTable:
    policies: list[str]
    categories: list[tuple[str, list[str]]]  # category -> tasks, in first-seen order
    cells: dict[str, dict[str, float | None]]  # task -> policy -> success rate
    means: dict[str, dict[str, float | None]]  # category (and "all") -> policy -> mean
    # task -> policy -> 95% Wilson interval (measured columns only)
    intervals: dict[str, dict[str, tuple[float, float]]] = field(default_factory=dict)
    sources: list[str] = field(default_factory=list)  # where reference columns come from
    # category (and "all") -> policy -> (tasks it evaluated, tasks in the row), where fewer
    partial: dict[str, dict[str, tuple[int, int]]] = field(default_factory=dict)

    def mean_row(self, cat: str) -> dict[str, float | None]:
        """The row's means, less those over only some of its tasks (not comparable)."""
        return {p: None if p in self.partial.get(cat, {}) else v
                for p, v in self.means[cat].items()}


def load_results(run_dir: pathlib.Path) -> dict:
    path = run_dir / RESULTS_FILE
    if not path.exists():
        raise MergeError(f"{run_dir} has no {RESULTS_FILE}: pass evaluation run folders "
                         "(runs/eval/<split>/<policy>/<run>)")
    return json.loads(path.read_text())


def expand_runs(paths: list[pathlib.Path]) -> list[pathlib.Path]:
    """Each path, or the runs below it (in job order) when it is no run itself."""
    runs = []
    for path in paths:
        if (path / RESULTS_FILE).exists() or not path.is_dir():
            runs.append(path)
            continue
        found = [r.parent for r in path.rglob(RESULTS_FILE)]
        if not found:
            raise MergeError(f"{path} has no {RESULTS_FILE}, nor any run below it: pass "
                             "evaluation run folders (runs/eval/<split>/<policy>/<run>) or a "
                             "sweep's folder (runs/eval/multirun/<time>)")
        runs += sorted(found, key=lambda r: (int(r.name) if r.name.isdigit() else -1, str(r)))
    return runs


def _labels(summaries: list[dict], run_dirs: list[pathlib.Path]) -> list[str]:
    """A column per run: its policy label, shared by runs of that label on disjoint
    tasks, else made unique with the run folder's name."""
    labels = [s["policy_label"] for s in summaries]
    tasks = [[t["task"] for t in s["tasks"]] for s in summaries]
    out = []
    for label, d in zip(labels, run_dirs, strict=True):
        same = [ts for lb, ts in zip(labels, tasks, strict=True) if lb == label]
        flat = [t for ts in same for t in ts]
        disjoint = len(flat) == len(set(flat))
        out.append(label if len(same) == 1 or disjoint else f"{label} ({d.name})")
    return out


def _mean(values: list[float | None]) -> float | None:
    present = [v for v in values if v is not None]
    return sum(present) / len(present) if present else None


def merge_runs(run_dirs: list[pathlib.Path], reference: Reference | None = None) -> MergedTable:
    """One table over every task any run evaluated; a policy's means cover the tasks
    it evaluated (a missing cell shows as '-'; a mean over only some of a row's tasks is
    marked with their count and never the row's best). A reference's columns follow, on
    the same tasks, so that their means compare with ours."""
    if not run_dirs:
        raise MergeError("name at least one evaluation run folder to merge")
    run_dirs = expand_runs(run_dirs)
    summaries = [load_results(d) for d in run_dirs]
    columns = _labels(summaries, run_dirs)
    policies = list(dict.fromkeys(columns))
    if reference is not None:
        policies += [reference.label(c) for c in reference.columns]
    order: dict[str, list[str]] = {}
    cells: dict[str, dict[str, float | None]] = {}
    intervals: dict[str, dict[str, tuple[float, float]]] = {}
    for policy, summary in zip(columns, summaries, strict=True):
        for t in summary["tasks"]:
            if t["task"] not in cells:
                order.setdefault(t["category"], []).append(t["task"])
                cells[t["task"]] = dict.fromkeys(policies)
            cells[t["task"]][policy] = t["success_rate"]
            intervals.setdefault(t["task"], {})[policy] = (t["ci_low"], t["ci_high"])
    if not cells:
        raise MergeError("none of the runs has a finished task to tabulate")
    if reference is not None:
        for task, row in cells.items():
            published = reference.tasks.get(task, ())
            for column, rate in zip(reference.columns, published, strict=False):
                row[reference.label(column)] = rate
    means = {cat: {p: _mean([cells[t][p] for t in tasks]) for p in policies}
             for cat, tasks in order.items()}
    means["all"] = {p: _mean([row[p] for row in cells.values()]) for p in policies}
    rows = {**order, "all": list(cells)}
    partial = {cat: {p: (k, len(tasks)) for p in policies
                     if 0 < (k := sum(cells[t][p] is not None for t in tasks)) < len(tasks)}
               for cat, tasks in rows.items()}
    sources = [] if reference is None else [reference.source]
    return MergedTable(policies, list(order.items()), cells, means, intervals, sources,
                       partial)


def _best(row: dict[str, float | None]) -> set[str]:
    """Policies holding the row's best value, unless every policy ties."""
    values = [v for v in row.values() if v is not None]
    if len(set(values)) < 2:
        return set()
    top = max(values)
    return {p for p, v in row.items() if v == top}


def _cells(row: dict[str, float | None], bold: str,
           intervals: dict[str, tuple[float, float]] | None = None,
           partial: dict[str, tuple[int, int]] | None = None) -> list[str]:
    """Each value (the row's best in bold), with its interval where one is given, or
    the count of tasks behind a partial mean."""
    intervals, partial = intervals or {}, partial or {}
    best = _best({p: v for p, v in row.items() if p not in partial})
    out = []
    for p, v in row.items():
        text = "-" if v is None else bold.format(f"{v:.2f}") if p in best else f"{v:.2f}"
        if v is not None and p in intervals:
            text += " [{:.2f}, {:.2f}]".format(*intervals[p])
        if v is not None and p in partial:
            text += " ({}/{})".format(*partial[p])
        out.append(text)
    return out


def _mean_cells(table: MergedTable, cat: str, bold: str) -> list[str]:
    return _cells(table.means[cat], bold, partial=table.partial.get(cat))


def markdown(table: MergedTable) -> str:
    lines = ["| category | task | " + " | ".join(table.policies) + " |",
             "|---|---|" + "---:|" * len(table.policies)]
    for cat, tasks in table.categories:
        for t in tasks:
            lines.append(f"| {cat} | {t} | " + " | ".join(
                _cells(table.cells[t], "**{}**", table.intervals.get(t))) + " |")
        lines.append(f"| *{cat}* | *mean* | " + " | ".join(_mean_cells(table, cat, "**{}**"))
                     + " |")
    lines.append("| **all** | **mean** | " + " | ".join(_mean_cells(table, "all", "**{}**"))
                 + " |")
    if table.intervals:
        lines.append("\nMeasured cells: success rate [95% Wilson interval over episodes].")
    if any(table.partial.values()):
        lines.append("A mean marked (k/n) covers only the k of the row's n tasks that "
                     "policy has: not comparable with the others.")
    lines += [f"Columns marked (paper): {s}." for s in table.sources]
    return "\n".join(lines) + "\n"


def latex(table: MergedTable) -> str:
    """Needs `\\usepackage{booktabs,multirow}`."""
    cols = "ll" + "c" * len(table.policies)
    lines = [rf"\begin{{tabular}}{{{cols}}}", r"\toprule",
             "Category & Task & " + " & ".join(map(tex_escape, table.policies)) + r" \\",
             r"\midrule"]
    bold = r"\textbf{{{}}}"
    for cat, tasks in table.categories:
        for i, t in enumerate(tasks):
            head = rf"\multirow{{{len(tasks)}}}{{*}}{{{tex_escape(cat)}}}" if i == 0 else ""
            lines.append(f"{head} & {tex_escape(t)} & "
                         + " & ".join(_cells(table.cells[t], bold)) + r" \\")
        lines += [r"\cmidrule{2-" + str(2 + len(table.policies)) + "}",
                  " & Mean & " + " & ".join(_mean_cells(table, cat, bold)) + r" \\",
                  r"\midrule"]
    lines += [r"\multicolumn{2}{l}{Mean} & " + " & ".join(_mean_cells(table, "all", bold))
              + r" \\", r"\bottomrule", r"\end{tabular}"]
    return "\n".join(lines) + "\n"


def csv_text(table: MergedTable) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    measured = [p for p in table.policies
                if any(p in row for row in table.intervals.values())]
    writer.writerow(["category", "task", *table.policies,
                     *(f"{p} {b}" for p in measured for b in ("ci_low", "ci_high"))])

    def fmt(row: dict[str, float | None]) -> list[str]:
        return ["" if v is None else f"{v:.4f}" for v in row.values()]

    def bounds(task: str | None) -> list[str]:
        ci = table.intervals.get(task, {}) if task else {}
        return [f"{ci[p][i]:.4f}" if p in ci else "" for p in measured for i in (0, 1)]

    for cat, tasks in table.categories:
        writer.writerows([cat, t, *fmt(table.cells[t]), *bounds(t)] for t in tasks)
        writer.writerow([cat, "mean", *fmt(table.means[cat]), *bounds(None)])
    writer.writerow(["all", "mean", *fmt(table.means["all"]), *bounds(None)])
    return out.getvalue()


def write_merged(table: MergedTable, out_dir: pathlib.Path) -> dict[str, pathlib.Path]:
    """merged.{md,tex,csv} and the category chart merged.png in `out_dir`; the paths by
    format."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {}
    for fmt, text in (("md", markdown(table)), ("tex", latex(table)), ("csv", csv_text(table))):
        paths[fmt] = out_dir / f"merged.{fmt}"
        write_text(paths[fmt], text)
    paths["png"] = out_dir / "merged.png"
    merged_chart(table.categories, {c: table.mean_row(c) for c in table.means}, paths["png"])
    return paths
