"""Policy checkpoints: weights, EMA weights, normalizer, resolved config, action layout.

A checkpoint is one `torch.save` file written to a temp path and renamed. A training
run folder holds `best.pt` (lowest validation loss) and `last.pt`; passing a folder
resolves to its best, else its last, and a folder of run folders to its newest run.
"""

from __future__ import annotations

import os
import pathlib
from typing import Any

import torch

from dexbench.policies.common.protocol import PolicySpec

FORMAT = "dexbench-policy/1"
BEST, LAST = "best.pt", "last.pt"
META_KEYS = ("kind", "task", "embodiment", "obs", "groups", "shapes", "action_layout",
             "config", "epoch", "step", "val_loss", "dataset")


class CheckpointError(ValueError):
    """A checkpoint path that holds no usable checkpoint of the expected kind."""


def save_checkpoint(path: pathlib.Path, payload: dict[str, Any]) -> None:
    """Write `payload` (meta keys + `model`, `ema`, `normalizer`) whole or not at all."""
    missing = [k for k in (*META_KEYS, "model", "ema", "normalizer") if k not in payload]
    if missing:
        raise ValueError(f"checkpoint payload lacks {missing}")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    torch.save({**payload, "format": FORMAT}, tmp)
    os.replace(tmp, path)


def resolve_checkpoint(path: str | pathlib.Path) -> pathlib.Path:
    """The checkpoint file a path names: a file, a run folder, or a folder of runs."""
    path = pathlib.Path(path)
    if path.is_file():
        return path
    if not path.is_dir():
        raise CheckpointError(f"no checkpoint at {path}; train one with `python train.py "
                              "policy=<dp|dp3> task=<task>` or pass the .pt file")
    for name in (BEST, LAST):
        if (path / name).is_file():
            return path / name
    runs = sorted(p for p in path.iterdir() if p.is_dir() and any(
        (p / n).is_file() for n in (BEST, LAST)))
    if runs:
        return resolve_checkpoint(runs[-1])
    raise CheckpointError(f"{path} holds neither {BEST} nor {LAST} nor run folders with "
                          "them; point checkpoint= at a training run folder or a .pt file")


def load_checkpoint(path: str | pathlib.Path, kind: str) -> dict[str, Any]:
    """The payload of the checkpoint `path` resolves to; weights stay memory-mapped."""
    file = resolve_checkpoint(path)
    try:
        payload = torch.load(file, map_location="cpu", weights_only=True, mmap=True)
    except (RuntimeError, EOFError, OSError, ValueError) as err:
        raise CheckpointError(f"{file} is not a readable checkpoint ({err}); it may be "
                              "truncated: use another one or retrain") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"{file} is not a dexbench policy checkpoint ({FORMAT})")
    if payload.get("kind") != kind:
        raise CheckpointError(f"{file} holds a {payload.get('kind')!r} policy, not {kind!r}; "
                              f"pass policy={payload.get('kind')}")
    payload["path"] = str(file)
    return payload


def spec_of(payload: dict[str, Any]) -> PolicySpec:
    """What the env must look like for this checkpoint: no env-side history, since the
    chunking policy keeps its own window of frames (`ChunkedActor`)."""
    obs = payload["obs"]
    return PolicySpec(obs=obs if isinstance(obs, str) else tuple(obs), task=payload["task"],
                      embodiment=payload["embodiment"],
                      action_layout=tuple(payload["action_layout"]), history=0)
