"""`python -m dexbench merge <eval run> <eval run> ... [out=<folder>] [reference=<name>]`:
the paper-style table (tasks x policies, category means, best per row in bold, our cells
with their 95% intervals) in Markdown, LaTeX and CSV, written to `out` (default
`runs/eval/merged/<timestamp>/`) and printed. `reference=dexverse_table3` sets the
paper's published columns (`conf/reference/<name>.yaml`) beside ours."""

from __future__ import annotations

import datetime as dt
import json
import pathlib

import yaml

from dexbench.cli.config import CONF_DIR, ConfigError, runs_root
from dexbench.eval.merge import MergeError, Reference, markdown, merge_runs, write_merged

USAGE = ("usage: python -m dexbench merge <eval run folder> ... [out=<folder>] "
         "[reference=<name>]")


def load_reference(name: str) -> Reference:
    """`conf/reference/<name>.yaml`: published success rates, or an error naming those
    there are."""
    folder = CONF_DIR / "reference"
    path = folder / f"{name}.yaml"
    if not path.exists():
        known = sorted(p.stem for p in folder.glob("*.yaml"))
        raise ConfigError(f"reference={name} is not in conf/reference/; references: {known}")
    data = yaml.safe_load(path.read_text())
    return Reference(str(data["source"]), list(data["columns"]),
                     {t: [float(v) for v in vs] for t, vs in data["tasks"].items()})


def merge(argv: list[str]) -> int:
    if not argv or {"-h", "--help"} & set(argv):
        print(__doc__)
        return 0 if argv else 2
    options = dict(a.split("=", 1) for a in argv if "=" in a)
    unknown = sorted(set(options) - {"out", "reference"})
    if unknown:
        raise ConfigError(f"unknown option(s) {unknown}; {USAGE}")
    runs = [pathlib.Path(a) for a in argv if "=" not in a]
    try:
        reference = load_reference(options["reference"]) if "reference" in options else None
        table = merge_runs(runs, reference)
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
