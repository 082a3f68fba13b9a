"""Training metrics to CSV (always), TensorBoard (when installed) and W&B (when enabled).

W&B runs offline unless told otherwise, so training never needs an account or network.
"""

from __future__ import annotations

import csv
import importlib.util
import pathlib
from typing import Any

FIELDS = ("epoch", "step", "train_loss", "val_loss", "lr", "ema_decay", "elapsed_s")


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
        self._wandb = None
        if wandb and wandb.get("enabled"):
            try:
                import wandb as wandb_module
            except ImportError:
                raise ImportError("wandb.enabled=true needs `pip install wandb`") from None
            self._wandb = wandb_module.init(project=wandb.get("project", "dexbench"),
                                            mode=wandb.get("mode", "offline"),
                                            dir=str(run_dir), config=config)

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
