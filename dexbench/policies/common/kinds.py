"""The `spec`/`build` pair of a diffusion policy kind, shared by DP and DP3."""

from __future__ import annotations

import pathlib

from dexbench.policies.common.checkpoint import load_checkpoint, spec_of
from dexbench.policies.common.protocol import PolicySpec
from dexbench.policies.common.runner import DiffusionChunkPolicy, ModelFactory


def checkpoint_spec(kind: str, checkpoint: str | pathlib.Path) -> PolicySpec:
    return spec_of(load_checkpoint(checkpoint, kind))


def build_policy(kind: str, make_model: ModelFactory, checkpoint: str | pathlib.Path, env,
                 device: str | None = "auto") -> DiffusionChunkPolicy:
    return DiffusionChunkPolicy(load_checkpoint(checkpoint, kind), make_model, env, device)
