"""`python -m dexbench matrix split=baseline19 episodes=20 jobs=16`: the cross-embodiment
matrix, the scripted expert on every (task, embodiment) cell of a split.

Single-hand tasks run on the 24 single-hand embodiments, two-hand tasks on the 24
bimanual ones (`tasks=[...]`, `embodiments=[...]` narrow them). Each cell is an
`eval.py` run (`policy=expert`, the same episode keys) in its own folder
`runs/matrix/<split>/<task>/<embodiment>/`, so the command resumes: a complete cell is
skipped, an unfinished one keeps its finished episodes. Cells run in `jobs` processes,
one thread each; a line is printed per finished cell. Each arm cell also gets the
feasibility test of `dexbench/eval/feasibility.py` (the palm paths of the floating hand
over the first evaluation episodes, solved by the arm's IK). The folder's
`matrix.{md,csv,png}` and `summary.json` (`dexbench/eval/matrix.py`) are rewritten at the
end; `render_only=true` rebuilds them from the folder alone.
"""

from __future__ import annotations

import json
import os
import pathlib
import time
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from multiprocessing import active_children, get_context
from typing import Any

from omegaconf import DictConfig, ListConfig, OmegaConf

from dexbench.cli.app import Command, register
from dexbench.cli.config import ConfigError, load_config, positive_int, runs_root
from dexbench.data.meta import as_json
from dexbench.embodiments.builder import parse_embodiment
from dexbench.eval import matrix
from dexbench.eval.feasibility import reference_embodiment
from dexbench.tasks.registry import TASKS

ENV_KEYS = ("sim", "camera", "visual", "physical", "seed", "num_envs")
THREAD_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")


@dataclass(frozen=True)
class Prepared:
    """A checked matrix: its tasks in split order, its cells and the eval config a
    cell starts from."""

    split: str
    tasks: list[dict]  # {"task", "category", "bimanual"} in split order
    cells: list[tuple[str, str]]
    base: dict  # an eval config (policy=expert) without task and embodiment
    identity: dict
    missing: list[str]  # split tasks not implemented


def _names(value: Any) -> list[str] | None:
    if value is None:
        return None
    if not isinstance(value, ListConfig):
        raise ConfigError(f"expected a list such as [A,B], got {value!r}")
    return [str(v) for v in value]


def split_tasks(cfg: DictConfig) -> tuple[str, list[dict], list[str]]:
    """(split name, its implemented tasks in order, the others)."""
    split = cfg.get("split")
    if not isinstance(split, DictConfig) or "categories" not in split:
        raise ConfigError("split must name a file of conf/split/, e.g. split=baseline19")
    tasks, missing = [], []
    for category, names in split.categories.items():
        for name in map(str, names):
            if name in TASKS:
                tasks.append({"task": name, "category": str(category),
                              "bimanual": bool(TASKS[name].bimanual)})
            else:
                missing.append(name)
    return str(split.name), tasks, missing


def folder_of(cfg: DictConfig) -> tuple[str, str]:
    """`matrix` and the matrix's folder name (`name=`, else the split's)."""
    if cfg.get("name"):
        return "matrix", str(cfg.name)
    split = cfg.get("split")
    return "matrix", str(split.name) if isinstance(split, DictConfig) else "matrix"


def base_config(cfg: DictConfig) -> dict:
    """The eval config every cell starts from: the expert, `episodes`, the matrix's
    environment settings, no progress bar."""
    base = load_config("eval", ["policy=expert", "progress=false"])
    for key in ENV_KEYS:
        base[key] = cfg[key]
    base.episodes = int(cfg.episodes)
    return OmegaConf.to_container(base, resolve=True)


def identity(cfg: DictConfig, split: str) -> dict:
    """What fixes every cell's outcome: a matrix folder holds one identity (as JSON
    stores it, so that a tuple from a structured config compares equal to its stored list)."""
    sim = {k: v for k, v in OmegaConf.to_container(cfg.sim, resolve=True).items()
           if k != "nthread"}
    return as_json({"split": split, "episodes": int(cfg.episodes), "seed": int(cfg.seed),
                    "sim": sim,
                    **{k: OmegaConf.to_container(cfg[k], resolve=True)
                       for k in ("visual", "physical")},
                    "probe_episodes": int(cfg.feasibility.probe_episodes)})


def check(cfg: DictConfig, overrides: list[str]) -> Prepared:
    """Split, subsets, counts, and a folder that holds this very matrix (or none)."""
    split, tasks, missing = split_tasks(cfg)
    positive_int(cfg, "episodes")
    positive_int(cfg, "jobs")
    probes = cfg.feasibility.probe_episodes
    if isinstance(probes, bool) or not isinstance(probes, int) or probes < 0:
        raise ConfigError(f"feasibility.probe_episodes must be a whole number >= 0, got "
                          f"{probes!r}")
    wanted = _names(cfg.get("tasks"))
    if wanted is not None:
        known = {t["task"] for t in tasks}
        unknown = [t for t in wanted if t not in known]
        if unknown:
            raise ConfigError(f"tasks={unknown} are not implemented tasks of split {split}: "
                              f"choose from {', '.join(t['task'] for t in tasks)}")
        tasks = [t for t in tasks if t["task"] in wanted]
    embodiments = _names(cfg.get("embodiments"))
    for name in embodiments or []:
        parse_embodiment(name)
    cells = matrix.pairs([(t["task"], t["bimanual"]) for t in tasks], embodiments)
    if not cells:
        raise ConfigError("no (task, embodiment) cell: single-hand tasks need single-hand "
                          "embodiments, two-hand tasks bimanual ones")
    no_expert = sorted({t for t, _ in cells if getattr(TASKS[t], "expert", None) is None})
    if no_expert:
        raise ConfigError(f"no scripted expert for {', '.join(no_expert)}; leave them out "
                          "with tasks=[...]")
    ident = identity(cfg, split)
    root = runs_root() / "/".join(folder_of(cfg))
    info_file = root / matrix.MATRIX_FILE
    if cfg.render_only:
        if not info_file.exists():
            raise ConfigError(f"render_only=true: {root} holds no matrix ({matrix.MATRIX_FILE})")
    elif info_file.exists():
        stored = json.loads(info_file.read_text())["identity"]
        changed = sorted(k for k in {*stored, *ident} if stored.get(k) != ident.get(k))
        if changed:
            raise ConfigError(f"{root} holds a matrix with other settings "
                              f"({', '.join(changed)}); choose another name= or keep them")
    return Prepared(split, tasks, cells, base_config(cfg), ident, missing)


def _single_thread() -> None:
    import torch

    torch.set_num_threads(1)


def run_cell(base: dict, task: str, embodiment: str, folder: str) -> tuple[matrix.Cell, float]:
    """Evaluate one cell into `folder` (resuming what it holds): the cell and seconds."""
    from dexbench.cli import eval as eval_cli
    from dexbench.eval.session import open_run
    from dexbench.eval.session import run as run_eval

    started = time.perf_counter()
    cfg = OmegaConf.create({**base, "task": task, "embodiment": embodiment})
    prepared = eval_cli.check(cfg, [])
    run_dir = open_run(prepared.spec, pathlib.Path(folder),
                       OmegaConf.to_container(prepared.cfg, resolve=True))
    _, summary = run_eval(prepared.spec, prepared.plans, prepared.skipped, run_dir)
    if summary is None:  # interrupted: the evaluator kept the finished episodes
        raise KeyboardInterrupt
    root = pathlib.Path(folder).parents[1]
    return matrix.read_cell(root, task, embodiment), time.perf_counter() - started


def run_feasibility(base: dict, task: str, reference: str, probes: int,
                    targets: list[tuple[str, str]]) -> list[tuple[str, bool, str]]:
    """Record the reference's palm paths on `task` and measure each target arm
    embodiment's reach of them into its folder: (embodiment, feasible, reason) each."""
    from dexbench.cli import eval as eval_cli
    from dexbench.eval import feasibility
    from dexbench.eval.tables import write_text

    cfg = OmegaConf.create({**base, "task": task, "embodiment": reference, "episodes": probes})
    prepared = eval_cli.check(cfg, [])
    paths = feasibility.record_palm_paths(prepared.spec, prepared.plans[0], probes)
    out = []
    for embodiment, folder in targets:
        measurement = feasibility.measure(embodiment, paths, TASKS[task].workspace)
        pathlib.Path(folder).mkdir(parents=True, exist_ok=True)
        write_text(pathlib.Path(folder) / matrix.FEASIBILITY_FILE,
                   json.dumps(measurement, indent=2) + "\n")
        out.append((embodiment, *feasibility.verdict(measurement)))
    return out


def _jobs(prepared: Prepared, root: pathlib.Path, probes: int
          ) -> tuple[list[tuple[str, str, str, list]], list[tuple[str, str]]]:
    """(feasibility jobs: task, reference, label, targets; cells to evaluate), writing the
    floating cells' reference records on the way."""
    from dexbench.eval import feasibility
    from dexbench.eval.tables import write_text

    probe: dict[tuple[str, str], list[tuple[str, str]]] = {}
    todo = []
    for task, emb in prepared.cells:
        folder = matrix.cell_dir(root, task, emb)
        if probes and not (folder / matrix.FEASIBILITY_FILE).exists():
            ref = reference_embodiment(emb)
            if ref == emb:
                folder.mkdir(parents=True, exist_ok=True)
                write_text(folder / matrix.FEASIBILITY_FILE, json.dumps(
                    feasibility.reference_measurement(emb), indent=2) + "\n")
            else:
                probe.setdefault((task, ref), []).append((emb, str(folder)))
        if not matrix.cell_complete(folder, prepared.identity["episodes"]):
            todo.append((task, emb))
    feas = [(task, ref, f"{task} x {ref} (reference)", targets)
            for (task, ref), targets in probe.items()]
    return feas, todo


def write_info(prepared: Prepared, root: pathlib.Path) -> None:
    from dexbench.eval.tables import write_text

    root.mkdir(parents=True, exist_ok=True)
    info = {"identity": prepared.identity, "split": prepared.split,
            "episodes": prepared.identity["episodes"],
            "tasks": matrix_tasks(prepared, root), "missing": prepared.missing}
    write_text(root / matrix.MATRIX_FILE, json.dumps(info, indent=2) + "\n")


def matrix_tasks(prepared: Prepared, root: pathlib.Path) -> list[dict]:
    """The split's tasks: those of this run, and those an earlier run (a subset) left in
    the folder, in split order."""
    _, tasks, _ = split_tasks(load_config("matrix", [f"split={prepared.split}"]))
    ours = {t["task"] for t in prepared.tasks}
    return [t for t in tasks if t["task"] in ours or (root / t["task"]).is_dir()]


def run(cfg: DictConfig, prepared: Prepared, out: pathlib.Path) -> int:
    root = out
    if cfg.render_only:
        summary = matrix.write_outputs(root)
        print((root / matrix.MD_FILE).read_text())
        print(json.dumps({k: summary[k] for k in ("share_feasible_at_bar", "embodiments_ok",
                                                  "tasks_ok", "accepted")}))
        return 0
    write_info(prepared, root)
    probes = int(cfg.feasibility.probe_episodes)
    feas, todo = _jobs(prepared, root, probes)
    total = len(prepared.cells)
    if prepared.missing:
        print(f"not implemented, left out: {', '.join(prepared.missing)}")
    print(f"matrix {prepared.split}: {total} cells, {total - len(todo)} complete, "
          f"{len(todo)} to evaluate, {len(feas)} feasibility probes; jobs={cfg.jobs}; {root}",
          flush=True)
    try:
        failed = _execute(prepared, root, feas, todo, int(cfg.jobs), probes)
    except KeyboardInterrupt:
        matrix.write_outputs(root)
        print(f"\ninterrupted: finished episodes are kept in {root}; the same command "
              "resumes")
        return 130
    summary = matrix.write_outputs(root)
    print((root / matrix.MD_FILE).read_text())
    print(json.dumps({"run_dir": str(root), "complete": summary["complete"],
                      "cells": summary["cells"], "failed": failed,
                      "share_feasible_at_bar": summary["share_feasible_at_bar"],
                      "accepted": summary["accepted"]}))
    return 0 if not failed and summary["complete"] == summary["cells"] else 1


def _execute(prepared: Prepared, root: pathlib.Path, feas: list, todo: list, jobs: int,
             probes: int) -> int:
    """Run the feasibility probes and the cells, `jobs` at a time, printing a line as
    each ends; the number that failed."""
    base = prepared.base
    calls: list[tuple[str, Any, tuple]] = [
        (label, run_feasibility, (base, task, ref, probes, targets))
        for task, ref, label, targets in feas]
    calls += [(f"{task} x {emb}", run_cell,
               (base, task, emb, str(matrix.cell_dir(root, task, emb)))) for task, emb in todo]
    failed, done, width = 0, 0, len(str(len(todo)))

    def report(label: str, fn: Any, result: Any = None, error: BaseException | None = None
               ) -> None:
        nonlocal failed, done
        if error is not None:
            failed += 1
            print(f"error: {label}: {type(error).__name__}: {error}", flush=True)
            return
        if fn is run_feasibility:
            verdicts = ", ".join(f"{e} {'feasible' if ok else 'infeasible'}"
                                 for e, ok, _ in result)
            print(f"[feasibility] {label}: {verdicts}", flush=True)
            return
        done += 1
        cell, seconds = result
        print(f"[{done:>{width}}/{len(todo)}] {label}: {matrix.rate_line(cell)} "
              f"{seconds:.0f} s", flush=True)
        matrix.write_outputs(root, plot=False)

    if jobs == 1:
        _single_thread()
        for label, fn, args in calls:
            try:
                report(label, fn, fn(*args))
            except Exception as err:  # one cell's failure must not stop the matrix
                report(label, fn, error=err)
        return failed
    for var in THREAD_VARS:
        os.environ.setdefault(var, "1")
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn"),
                               initializer=_single_thread)
    try:
        pending: dict[Future, tuple[str, Any]] = {
            pool.submit(fn, *args): (label, fn) for label, fn, args in calls}
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                label, fn = pending.pop(future)
                error = future.exception()
                report(label, fn, None if error else future.result(), error)
    except KeyboardInterrupt:
        # Queued calls would still start; every finished episode is already on disk.
        pool.shutdown(wait=False, cancel_futures=True)
        for child in active_children():
            child.terminate()
        raise
    pool.shutdown()
    return failed


def run_dir(cfg: DictConfig) -> tuple[str, str]:
    return folder_of(cfg)


MATRIX = register(Command("matrix", run, check, run_dir))
main = MATRIX.main
