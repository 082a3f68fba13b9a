"""The Hydra mains behind every entry point, and what they share.

A command is a `Command`: `check(cfg, overrides)` validates what a user can get wrong and
returns what it prepared; `run(cfg, prepared, out)` does the work in the job's output
folder `out` (Hydra's `hydra.runtime.output_dir`, from `hydra.run.dir` /
`hydra.sweep.dir` in conf/, laid out by the command's `run_dir`). The check runs before
Hydra writes anything: in `CheckFirst.on_run_start`, and with `-m` for every job of a
basic sweep in `on_multirun_start` (its light `validate` where a command has one); a
single run reuses what it prepared. Our errors are
one line, `error: ...`, and exit status 2: Hydra passes `SystemExit` through its
callbacks and jobs, where it would turn an exception into a warning or a report of
several lines. A sweep job's error is its line (and `error.txt` in its folder); the
other jobs go on, and the sweep exits 2 when any failed.
"""

from __future__ import annotations

import datetime as dt
import pathlib
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import hydra
from hydra import compose
from hydra._internal.utils import get_args_parser
from hydra.core.hydra_config import HydraConfig
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import HydraException
from hydra.experimental.callback import Callback
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf, open_dict, read_write
from omegaconf.errors import OmegaConfBaseException

from dexbench.cli.config import CONF_DIR, ConfigError, load_config, runs_root
from dexbench.cli.errors import USER_ERRORS

BASIC_SWEEPER = "hydra._internal.core_plugins.basic_sweeper.BasicSweeper"


ERROR_FILE = "error.txt"


def fail(line: str) -> None:
    """Print the one error line and exit 2 (`SystemExit` passes through Hydra)."""
    print(line, file=sys.stderr)
    raise SystemExit(2)


@dataclass(frozen=True)
class Command:
    """One entry point: its primary config `conf/<name>.yaml` and its three steps."""

    name: str
    run: Callable[[DictConfig, Any, pathlib.Path | None], int]
    check: Callable[[DictConfig, list[str]], Any] = lambda cfg, overrides: None
    # The run folder under `runs/` as (layout, leaf): `layout` starts with the command's
    # folder (`eval/<split>/<policy>`), `leaf` may hold `{stamp}`. None: no run folder.
    run_dir: Callable[[DictConfig], tuple[str, str]] | None = None
    # What a sweep tests for every job before the first starts; None: `check`. A command
    # whose check is heavy (loading data) gives a light one, so the jobs do the heavy
    # part in parallel.
    validate: Callable[[DictConfig, list[str]], Any] | None = None

    def folder(self, cfg: DictConfig, when: str) -> pathlib.Path:
        """A single run's folder, stamped `when`."""
        layout, leaf = self.run_dir(cfg)
        return runs_root() / layout / leaf.format(stamp=when)

    def main(self, argv: list[str]) -> int:
        """Programmatic form of the command: `key=value` overrides, no Hydra outputs."""
        cfg = load_config(self.name, argv)
        prepared = self.check(cfg, argv)
        out = None if self.run_dir is None else self.folder(cfg, stamp())
        return self.run(cfg, prepared, out)


COMMANDS: dict[str, Command] = {}
_PREPARED: dict[str, tuple[str, Any]] = {}  # command -> (its config as YAML, what check gave)


def stamp() -> str:
    """A run folder's timestamp, unique to the microsecond."""
    return dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")


def _task_config(config: DictConfig) -> DictConfig:
    """`config` without its `hydra` node, as a job sees it."""
    cfg = OmegaConf.create(OmegaConf.to_container(config, resolve=False))
    with read_write(cfg), open_dict(cfg):
        cfg.pop("hydra", None)
    return cfg


def _checked(command: Command, cfg: DictConfig, overrides: list[str]) -> Any:
    try:
        return command.check(cfg, overrides)
    except USER_ERRORS as err:
        fail(f"error: {err}")


def _command(root: DictConfig) -> Command:
    return COMMANDS[str(root.hydra.job.config_name)]


def _run_dir(when: str, *, _root_: DictConfig) -> str:
    """`${dexbench.run_dir:<stamp>}`: a single run's folder."""
    return str(_command(_root_).folder(_task_config(_root_), when))


def _sweep_dir(when: str, *, _root_: DictConfig) -> str:
    """`${dexbench.sweep_dir:<stamp>}`: `runs/<command folder>/multirun/<stamp>`."""
    layout, _ = _command(_root_).run_dir(_task_config(_root_))
    return str(runs_root() / layout.split("/")[0] / "multirun" / when)


def _job_dir(*, _root_: DictConfig) -> str:
    """`${dexbench.job_dir:}`: a sweep job's folder in the sweep's: the run layout below
    the command's folder, then the job number."""
    layout, _ = _command(_root_).run_dir(_task_config(_root_))
    return str(pathlib.Path(*layout.split("/")[1:], str(_root_.hydra.job.num)))


OmegaConf.register_new_resolver("dexbench.run_dir", _run_dir, replace=True)
OmegaConf.register_new_resolver("dexbench.sweep_dir", _sweep_dir, replace=True)
OmegaConf.register_new_resolver("dexbench.job_dir", _job_dir, replace=True)


def sweep_jobs(config: DictConfig) -> list[list[str]] | None:
    """Each job's overrides of a `-m` run, or None when the sweeper is not the basic one."""
    if OmegaConf.select(config, "hydra.sweeper._target_") != BASIC_SWEEPER:
        return None
    from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

    parsed = OverridesParser.create().parse_overrides(list(config.hydra.overrides.task))
    return [job for batch in BasicSweeper.split_arguments(parsed, None) for job in batch]


class CheckFirst(Callback):
    """Validates before Hydra creates a run folder or writes `.hydra/`; after a sweep,
    exits 2 if a job failed."""

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        command = COMMANDS[str(config.hydra.job.config_name)]
        cfg = _task_config(config)
        prepared = _checked(command, cfg, list(config.hydra.overrides.task))
        _PREPARED[command.name] = (OmegaConf.to_yaml(cfg), prepared)

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        command = COMMANDS[str(config.hydra.job.config_name)]
        for job in sweep_jobs(config) or []:
            try:
                (command.validate or command.check)(
                    compose(config_name=command.name, overrides=job), job)
            except (*USER_ERRORS, HydraException, OmegaConfBaseException) as err:
                fail(f"error: job {' '.join(job)}: {' '.join(str(err).split())}")

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        failed = sorted(pathlib.Path(str(config.hydra.sweep.dir)).rglob(ERROR_FILE))
        if failed:
            fail(f"error: {len(failed)} job(s) failed: "
                 f"{', '.join(str(p.parent) for p in failed)}")


def _prepared(command: Command, cfg: DictConfig) -> Any:
    """What `CheckFirst` prepared for this very config, else a fresh check."""
    key, prepared = _PREPARED.pop(command.name, (None, None))
    if key is not None and key == OmegaConf.to_yaml(cfg):
        return prepared
    return command.check(cfg, list(HydraConfig.get().overrides.task))


def register(command: Command) -> Command:
    COMMANDS[command.name] = command
    return command


def hydra_main(command: Command) -> Callable[[], None]:
    """The Hydra main of `command` (`--help`, `-m`, `--cfg`, `hydra.*` overrides...).

    A single run exits with the command's status; a sweep job returns it so that the
    other jobs run.
    """
    register(command)

    @hydra.main(config_path=str(CONF_DIR), config_name=command.name, version_base="1.3")
    def task(cfg: DictConfig) -> int:
        hc = HydraConfig.get()
        out = pathlib.Path(hc.runtime.output_dir) if command.run_dir is not None else None
        try:
            code = command.run(cfg, _prepared(command, cfg), out)
        except USER_ERRORS as err:
            if hc.mode == RunMode.RUN:
                fail(f"error: {err}")
            line = f"error: job {' '.join(hc.overrides.task)}: {err}"
            print(line, file=sys.stderr)
            (pathlib.Path(hc.runtime.output_dir) / ERROR_FILE).write_text(line + "\n")
            return 2
        if code and hc.mode == RunMode.RUN:
            sys.exit(code)
        return code

    def entry() -> None:
        _compose_first(command, sys.argv[1:])
        task()
        sys.exit(0)

    return entry


def _compose_first(command: Command, argv: list[str]) -> None:
    """The overrides (each job's with `-m`) composed once before Hydra runs: a wrong key
    or value is then one `error:` line (Hydra's own report spans several)."""
    args = get_args_parser().parse_known_args(argv)[0]
    if (args.help or args.hydra_help or args.cfg or args.info or args.shell_completion
            or args.config_name or args.config_dir or args.config_path
            or args.experimental_rerun):
        return
    ours = [o for o in args.overrides if not o.lstrip("+~").startswith(("hydra.", "hydra/"))]
    try:
        jobs = [ours]
        if args.multirun:
            from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

            parsed = OverridesParser.create().parse_overrides(ours)
            jobs = [job for batch in BasicSweeper.split_arguments(parsed, None) for job in batch]
        for job in jobs:
            load_config(command.name, job)
    except (ConfigError, HydraException) as err:
        fail(f"error: {' '.join(str(err).split())}")


def dispatch(verbs: dict[str, Command], argv: list[str], usage: str) -> None:
    """`<script> <verb> key=value ...`: the verb's Hydra main sees the rest of argv."""
    if not argv or argv[0] not in verbs:
        print(usage, file=sys.stderr)
        raise SystemExit(2)
    verb = argv[0]
    sys.argv = [f"{sys.argv[0]} {verb}", *argv[1:]]
    hydra_main(verbs[verb])()


