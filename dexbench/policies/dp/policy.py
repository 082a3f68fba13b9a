"""The `dp` policy kind: checkpoints of `python train.py policy=dp`, run on a batched env."""

from __future__ import annotations

import pathlib
from collections.abc import Mapping
from typing import Any

from dexbench.policies.common.kinds import build_policy, checkpoint_spec
from dexbench.policies.common.protocol import PolicySpec
from dexbench.policies.common.runner import DiffusionChunkPolicy
from dexbench.policies.dp.model import make_model

KIND = "dp"


def spec(checkpoint: str | pathlib.Path, options: Mapping[str, Any]) -> PolicySpec:
    """Task, embodiment, observation preset and action layout of a checkpoint."""
    return checkpoint_spec(KIND, checkpoint)


def build(checkpoint: str | pathlib.Path, env, device: str | None,
          options: Mapping[str, Any]) -> DiffusionChunkPolicy:
    """The checkpoint's EMA policy for `env`; refuses an env of another action layout."""
    return build_policy(KIND, make_model, checkpoint, env, device)
