"""1-D temporal U-Net over an action sequence, conditioned by FiLM (Diffusion Policy).

Each residual block convolves along time and scales/shifts its features with a
per-channel (scale, bias) predicted from the conditioning vector (diffusion-step
embedding concatenated with the observation features). Every stage but the last halves
the sequence and each up stage doubles it back (the first stage's skip is unused, as in
Diffusion Policy), so the horizon must be divisible by 2^(stages - 1).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import torch
from torch import nn


class SinusoidalEmbedding(nn.Module):
    """Transformer-style embedding of the (integer) diffusion step."""

    def __init__(self, dim: int) -> None:
        super().__init__()
        if dim % 2:
            raise ValueError(f"step embedding size must be even, got {dim}")
        self.dim = dim

    def forward(self, t: torch.Tensor) -> torch.Tensor:
        half = self.dim // 2
        freqs = torch.exp(-math.log(10000.0) * torch.arange(half, device=t.device) / (half - 1))
        angles = t.float()[:, None] * freqs[None]
        return torch.cat([angles.sin(), angles.cos()], dim=-1)


class ConvBlock(nn.Sequential):
    """Conv1d -> GroupNorm -> Mish, length preserving."""

    def __init__(self, cin: int, cout: int, kernel: int, groups: int) -> None:
        super().__init__(nn.Conv1d(cin, cout, kernel, padding=kernel // 2),
                         nn.GroupNorm(groups, cout), nn.Mish())


class FiLMResBlock(nn.Module):
    def __init__(self, cin: int, cout: int, cond_dim: int, kernel: int, groups: int) -> None:
        super().__init__()
        self.conv1 = ConvBlock(cin, cout, kernel, groups)
        self.conv2 = ConvBlock(cout, cout, kernel, groups)
        self.film = nn.Sequential(nn.Mish(), nn.Linear(cond_dim, 2 * cout))
        self.skip = nn.Conv1d(cin, cout, 1) if cin != cout else nn.Identity()

    def forward(self, x: torch.Tensor, cond: torch.Tensor) -> torch.Tensor:
        h = self.conv1(x)
        scale, bias = self.film(cond)[:, :, None].chunk(2, dim=1)
        h = self.conv2(scale * h + bias)
        return h + self.skip(x)


class ConditionalUnet1D(nn.Module):
    """Predicts the noise (or the clean sample) of an (B, T, action_dim) sequence."""

    def __init__(self, action_dim: int, cond_dim: int, channels: Sequence[int] = (256, 512, 1024),
                 kernel_size: int = 5, n_groups: int = 8, step_embed_dim: int = 256,
                 blocks_per_stage: int = 2) -> None:
        super().__init__()
        if blocks_per_stage < 1:
            raise ValueError(f"blocks_per_stage must be >= 1, got {blocks_per_stage}")
        channels = list(channels)
        self.stages = len(channels)
        self.step_embed = nn.Sequential(
            SinusoidalEmbedding(step_embed_dim), nn.Linear(step_embed_dim, 4 * step_embed_dim),
            nn.Mish(), nn.Linear(4 * step_embed_dim, step_embed_dim))
        c = step_embed_dim + cond_dim

        def blocks(cin: int, cout: int) -> nn.ModuleList:
            return nn.ModuleList([FiLMResBlock(cin if i == 0 else cout, cout, c, kernel_size,
                                               n_groups) for i in range(blocks_per_stage)])

        dims = [action_dim, *channels]
        self.down = nn.ModuleList()
        for i, (cin, cout) in enumerate(itertools.pairwise(dims)):
            last = i == len(channels) - 1
            self.down.append(nn.ModuleList([
                blocks(cin, cout),
                nn.Identity() if last else nn.Conv1d(cout, cout, 3, stride=2, padding=1)]))
        self.mid = blocks(channels[-1], channels[-1])
        self.up = nn.ModuleList()
        for cout, cin in reversed(list(itertools.pairwise(channels))):
            self.up.append(nn.ModuleList([
                blocks(2 * cin, cout), nn.ConvTranspose1d(cout, cout, 4, stride=2, padding=1)]))
        self.final = nn.Sequential(ConvBlock(channels[0], channels[0], kernel_size, n_groups),
                                   nn.Conv1d(channels[0], action_dim, 1))

    def forward(self, sample: torch.Tensor, timestep: torch.Tensor,
                cond: torch.Tensor) -> torch.Tensor:
        """`sample` (B, T, A), `timestep` (B,) or scalar, `cond` (B, cond_dim)."""
        if sample.shape[1] % 2 ** (self.stages - 1):
            raise ValueError(f"horizon {sample.shape[1]} must be divisible by "
                             f"{2 ** (self.stages - 1)} for {self.stages} U-Net stages")
        timestep = torch.as_tensor(timestep, device=sample.device).expand(sample.shape[0])
        c = torch.cat([self.step_embed(timestep), cond], dim=-1)
        x = sample.transpose(1, 2)
        skips = []
        for res, down in self.down:
            for block in res:
                x = block(x, c)
            skips.append(x)
            x = down(x)
        for block in self.mid:
            x = block(x, c)
        for res, up in self.up:
            x = torch.cat([x, skips.pop()], dim=1)
            for block in res:
                x = block(x, c)
            x = up(x)
        return self.final(x).transpose(1, 2)
