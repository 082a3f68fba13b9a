"""State DP (paper appendix): the `state` preset's groups, flattened per frame, through
an MLP encoder (256 hidden -> 128 per frame), To frames concatenated as the U-Net's
FiLM conditioning."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import torch
from torch import nn

from dexbench.policies.common.diffusion import DiffusionPolicyModel

OBS = "state"
GROUPS = ("policy", "proprio", "contact", "state", "goal")


def input_groups(available: Iterable[str]) -> list[str]:
    """The state groups a dataset (or env) has, in a fixed order."""
    have = set(available)
    groups = [g for g in GROUPS if g in have]
    if "proprio" not in groups:
        raise ValueError(f"state DP needs at least the proprio group; got {sorted(have)}")
    return groups


class StateEncoder(nn.Module):
    def __init__(self, groups: list[str], shapes: dict[str, tuple[int, ...]], hidden: int,
                 out: int) -> None:
        super().__init__()
        self.groups = groups
        dim = sum(math.prod(shapes[g]) for g in groups)
        self.mlp = nn.Sequential(nn.Linear(dim, hidden), nn.Mish(), nn.Linear(hidden, out))

    def forward(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        x = torch.cat([obs[g].flatten(2) for g in self.groups], dim=-1)  # (B, To, dim)
        return self.mlp(x).flatten(1)


def make_model(cfg: dict[str, Any], shapes: dict[str, tuple[int, ...]],
               action_dim: int) -> DiffusionPolicyModel:
    enc = cfg["encoder"]
    encoder = StateEncoder(input_groups(shapes), shapes, int(enc["hidden"]), int(enc["out"]))
    return DiffusionPolicyModel(encoder, int(enc["out"]) * int(cfg["n_obs_steps"]), action_dim,
                                int(cfg["horizon"]), dict(cfg["unet"]), dict(cfg["noise"]))
