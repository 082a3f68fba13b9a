"""`python -m dexbench validate dataset=<folder>`: is this dataset whole and current?"""

from __future__ import annotations

import json
import pathlib

from omegaconf import DictConfig

from dexbench.cli.app import Command, register
from dexbench.cli.config import ConfigError
from dexbench.data.validate import validate_dataset


def _check(cfg: DictConfig, overrides: list[str]) -> None:
    if not cfg.dataset:
        raise ConfigError("validate needs dataset=<dataset folder>")


def _run(cfg: DictConfig, _prepared: None, _out: pathlib.Path | None) -> int:
    """Print the report; exit 1 on errors (or on warnings with strict=true)."""
    report = validate_dataset(pathlib.Path(cfg.dataset), check_code=bool(cfg.check_code),
                              nthread=int(cfg.nthread))
    for error in report.errors:
        print(f"error: {error}")
    for warning in report.warnings:
        print(f"warning: {warning}")
    failed = not report.ok or (bool(cfg.strict) and bool(report.warnings))
    print(f"{report.root}: {'INVALID' if failed else 'ok'}")
    print(json.dumps({"dataset": str(report.root), "ok": not failed, **report.summary,
                      "errors": report.errors, "warnings": report.warnings}))
    return 1 if failed else 0


VALIDATE = register(Command("validate", _run, _check))
validate = VALIDATE.main
