"""`python -m dexbench merge <eval run> <eval run> ... [out=<folder>]`: the paper-style
table (tasks x policies, category means, best per row in bold) in Markdown, LaTeX and
CSV, written to `out` (default `runs/eval/merged/<timestamp>/`) and printed."""

from __future__ import annotations

import datetime as dt
import json
import pathlib

from dexbench.cli.config import ConfigError, runs_root
from dexbench.eval.merge import MergeError, markdown, merge_runs, write_merged

USAGE = "usage: python -m dexbench merge <eval run folder> ... [out=<folder>]"


def merge(argv: list[str]) -> int:
    if not argv or {"-h", "--help"} & set(argv):
        print(__doc__)
        return 0 if argv else 2
    options = dict(a.split("=", 1) for a in argv if "=" in a)
    unknown = sorted(set(options) - {"out"})
    if unknown:
        raise ConfigError(f"unknown option(s) {unknown}; {USAGE}")
    runs = [pathlib.Path(a) for a in argv if "=" not in a]
    try:
        table = merge_runs(runs)
    except MergeError as err:
        raise ConfigError(f"{err}; {USAGE}") from None
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
    out = pathlib.Path(options["out"]) if "out" in options else (
        runs_root() / "eval" / "merged" / stamp)
    paths = write_merged(table, out)
    (out / "runs.txt").write_text("".join(f"{r}\n" for r in runs))
    print(markdown(table))
    print(json.dumps({"policies": table.policies, "tasks": len(table.cells),
                      **{fmt: str(p) for fmt, p in paths.items()}}))
    return 0
