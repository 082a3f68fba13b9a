"""DP3 (paper appendix): a PointNet (per-point MLP with LayerNorm, max-pool, 64-d) on the
`pointcloud` preset's world-frame points, plus an MLP on proprioception (and the goal,
when the task has one), To frames concatenated as the U-Net's FiLM conditioning."""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from typing import Any

import torch
from torch import nn

from dexbench.policies.common.diffusion import DiffusionPolicyModel

OBS = "pointcloud"
LOW_DIM = ("proprio", "goal")


def input_groups(available: Iterable[str]) -> list[str]:
    have = set(available)
    if not {"pointcloud", "proprio"} <= have:
        raise ValueError(f"DP3 needs the pointcloud and proprio groups; got {sorted(have)}")
    return ["pointcloud", *(g for g in LOW_DIM if g in have)]


class PointNet(nn.Module):
    """Order-invariant encoding of (..., N, 3) points."""

    def __init__(self, hidden: Sequence[int], out: int) -> None:
        super().__init__()
        layers: list[nn.Module] = []
        dims = [3, *hidden]
        for cin, cout in itertools.pairwise(dims):
            layers += [nn.Linear(cin, cout), nn.LayerNorm(cout), nn.ReLU()]
        self.points = nn.Sequential(*layers)
        self.head = nn.Sequential(nn.Linear(dims[-1], out), nn.LayerNorm(out))

    def forward(self, points: torch.Tensor) -> torch.Tensor:
        return self.head(self.points(points).max(dim=-2).values)


class PointCloudEncoder(nn.Module):
    def __init__(self, groups: list[str], shapes: dict[str, tuple[int, ...]],
                 cfg: dict[str, Any]) -> None:
        super().__init__()
        self.low_dim = [g for g in groups if g != "pointcloud"]
        self.pointnet = PointNet(list(cfg["point_hidden"]), int(cfg["point_out"]))
        dim = sum(math.prod(shapes[g]) for g in self.low_dim)
        state = int(cfg["state_out"])
        self.state = nn.Sequential(nn.Linear(dim, state), nn.ReLU(), nn.Linear(state, state))
        self.out_dim = int(cfg["point_out"]) + state

    def forward(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        low = torch.cat([obs[g].flatten(2) for g in self.low_dim], dim=-1)  # (B, To, d)
        per_frame = torch.cat([self.pointnet(obs["pointcloud"]), self.state(low)], dim=-1)
        return per_frame.flatten(1)


def make_model(cfg: dict[str, Any], shapes: dict[str, tuple[int, ...]],
               action_dim: int) -> DiffusionPolicyModel:
    encoder = PointCloudEncoder(input_groups(shapes), shapes, cfg["encoder"])
    return DiffusionPolicyModel(encoder, encoder.out_dim * int(cfg["n_obs_steps"]), action_dim,
                                int(cfg["horizon"]), dict(cfg["unet"]), dict(cfg["noise"]))
