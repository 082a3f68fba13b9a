"""Training metrics to CSV (always), TensorBoard (when installed) and W&B (when enabled).

W&B runs offline unless told otherwise, so training never needs an account or network;
rl.py and eval.py start theirs here too (`start_wandb`), from the same `wandb:` block.
"""

from __future__ import annotations

import csv
import importlib.util
import pathlib
from typing import Any

FIELDS = ("epoch", "step", "train_loss", "val_loss", "lr", "ema_decay", "elapsed_s")
CURVE_KEYS = ("success_rate", "mean_reward", "env_steps", "wall_s", "episodes")
WANDB_MISSING = "wandb.enabled=true needs `pip install wandb`"


def wandb_missing(settings: dict[str, Any] | None) -> str | None:
    """Why W&B cannot log as `settings` (the config's `wandb:` block) ask; None: it can."""
    if settings and settings.get("enabled") and importlib.util.find_spec("wandb") is None:
        return WANDB_MISSING
    return None


def start_wandb(run_dir: pathlib.Path, config: dict[str, Any],
                settings: dict[str, Any] | None, job_type: str) -> Any:
    """The W&B run of train.py, rl.py or eval.py when `settings.enabled`, else None.

    Offline by default, written under `run_dir/wandb/`, so a run needs no account.
    """
    if not settings or not settings.get("enabled"):
        return None
    try:
        import wandb as wandb_module
    except ImportError:
        raise ImportError(WANDB_MISSING) from None
    return wandb_module.init(project=settings.get("project", "dexbench"),
                             mode=settings.get("mode", "offline"), dir=str(run_dir),
                             config=config, job_type=job_type)


def log_curve(run: Any, points: list[dict[str, Any]]) -> None:
    """rl.py's curve points (`dexbench/rl/vec_env.py`) as `rl/<key>` at their iteration."""
    if run is None:
        return
    for point in points:
        run.log({f"rl/{k}": point[k] for k in CURVE_KEYS if point.get(k) is not None},
                step=int(point["iteration"]))


def finish_wandb(run: Any, summary: dict[str, Any]) -> None:
    """Record the run's plain results (numbers and strings) as its summary and close it."""
    if run is None:
        return
    run.summary.update({k: v for k, v in summary.items() if isinstance(v, int | float | str)})
    run.finish()


class RunLog:
    def __init__(self, run_dir: pathlib.Path, config: dict[str, Any],
                 wandb: dict[str, Any] | None = None) -> None:
        self._file = open(run_dir / "metrics.csv", "w", newline="")  # noqa: SIM115
        self._csv = csv.DictWriter(self._file, fieldnames=FIELDS)
        self._csv.writeheader()
        self._tb = None
        if importlib.util.find_spec("tensorboard") is not None:
            from torch.utils.tensorboard import SummaryWriter
            self._tb = SummaryWriter(log_dir=str(run_dir / "tensorboard"))
        self._wandb = start_wandb(run_dir, config, wandb, "train")

    def scalar(self, name: str, value: float, step: int) -> None:
        """A per-step curve (TensorBoard and W&B only)."""
        if self._tb is not None:
            self._tb.add_scalar(name, value, step)
        if self._wandb is not None:
            self._wandb.log({name: value}, step=step)

    def epoch(self, row: dict[str, Any]) -> None:
        """One CSV row per epoch; its numbers also go to the other sinks."""
        self._csv.writerow({k: row.get(k) for k in FIELDS})
        self._file.flush()
        for key in ("train_loss", "val_loss", "lr"):
            if row.get(key) is not None:
                self.scalar(f"epoch/{key}", float(row[key]), int(row["step"]))

    def close(self) -> None:
        self._file.close()
        if self._tb is not None:
            self._tb.close()
        if self._wandb is not None:
            self._wandb.finish()
