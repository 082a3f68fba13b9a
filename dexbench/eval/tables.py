"""Success tables of one evaluation run (Markdown, CSV, LaTeX, JSON) from its summary.

Rows are grouped by category, each category closed by its mean, then the overall mean;
skipped tasks are listed under the table with the reason.
"""

from __future__ import annotations

import csv
import io
import json
import pathlib

CSV_COLUMNS = ("category", "task", "episodes", "successes", "success_rate", "ci_low",
               "ci_high", "mean_steps")


def write_text(path: pathlib.Path, text: str) -> None:
    """Write via a temp file and rename, so readers never see half a table."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def _rate(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def _ci(row: dict) -> str:
    return f"[{row['ci_low']:.2f}, {row['ci_high']:.2f}]"


def _tasks_of(summary: dict, category: str) -> list[dict]:
    return [t for t in summary["tasks"] if t["category"] == category]


def markdown(summary: dict) -> str:
    lines = [f"Policy `{summary['policy']}` on {summary['label']}: success rate with 95% "
             f"Wilson interval, {summary['episodes_per_task']} episodes per task.", "",
             "| category | task | success | 95% CI | episodes | mean steps |",
             "|---|---|---:|---|---:|---:|"]
    for cat in summary["categories"]:
        for t in _tasks_of(summary, cat["category"]):
            lines.append(f"| {cat['category']} | {t['task']} | {_rate(t['success_rate'])} | "
                         f"{_ci(t)} | {t['episodes']} | {t['mean_steps']:.0f} |")
        lines.append(f"| **{cat['category']}** | **mean** | **{_rate(cat['mean'])}** | | | |")
    lines.append(f"| **all** | **mean** | **{_rate(summary['overall'])}** | | "
                 f"{summary['episodes']} | |")
    notes = [f"- skipped {s['task']}: {s['reason']}" for s in summary["skipped"]]
    notes += [f"- {t['task']}: {t['episodes']} of {summary['episodes_per_task']} episodes so "
              "far (resume= continues)" for t in summary["tasks"]
              if t["episodes"] < summary["episodes_per_task"]]
    if summary["pending"]:
        notes.append(f"- not evaluated yet: {', '.join(summary['pending'])}")
    lines += ["", *notes] if notes else []
    return "\n".join(lines) + "\n"


def csv_text(summary: dict) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for t in summary["tasks"]:
        writer.writerow([t["category"], t["task"], t["episodes"], t["successes"],
                         f"{t['success_rate']:.4f}", f"{t['ci_low']:.4f}",
                         f"{t['ci_high']:.4f}", f"{t['mean_steps']:.1f}"])
    for cat in summary["categories"]:
        writer.writerow([cat["category"], "mean", "", "", f"{cat['mean']:.4f}", "", "", ""])
    if summary["overall"] is not None:
        writer.writerow(["all", "mean", summary["episodes"], "", f"{summary['overall']:.4f}",
                         "", "", ""])
    return out.getvalue()


def tex_escape(text: str) -> str:
    return text.replace("\\", r"\textbackslash{}").replace("_", r"\_").replace("&", r"\&")


def latex(summary: dict) -> str:
    """A booktabs table (needs `\\usepackage{booktabs}`)."""
    lines = [r"\begin{tabular}{llccc}", r"\toprule",
             r"Category & Task & Success & 95\% CI & Episodes \\", r"\midrule"]
    for cat in summary["categories"]:
        for t in _tasks_of(summary, cat["category"]):
            lines.append(f"{tex_escape(cat['category'])} & {tex_escape(t['task'])} & "
                         f"{_rate(t['success_rate'])} & {_ci(t)} & {t['episodes']} \\\\")
        lines += [rf"\multicolumn{{2}}{{l}}{{{tex_escape(cat['category'])} mean}} & "
                  rf"{_rate(cat['mean'])} & & \\", r"\midrule"]
    lines += [rf"\multicolumn{{2}}{{l}}{{Mean}} & {_rate(summary['overall'])} & & "
              rf"{summary['episodes']} \\", r"\bottomrule", r"\end{tabular}"]
    return "\n".join(lines) + "\n"


def write_tables(summary: dict, out_dir: pathlib.Path) -> dict[str, pathlib.Path]:
    """results.{md,csv,tex,json} in `out_dir`; the paths by format."""
    texts = {"md": markdown(summary), "csv": csv_text(summary), "tex": latex(summary),
             "json": json.dumps(summary, indent=2) + "\n"}
    paths = {}
    for fmt, text in texts.items():
        paths[fmt] = out_dir / f"results.{fmt}"
        write_text(paths[fmt], text)
    return paths
