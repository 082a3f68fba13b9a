"""Per-task min/max normalization to [-1, 1], the statistics stored in the checkpoint.

Diffusion models are trained on targets in [-1, 1] (the schedulers clip samples there),
so actions and observations are scaled per feature with the training set's range.
"""

from __future__ import annotations

import torch

EPS = 1e-6


class MinMaxNormalizer:
    """Maps each feature (last axis) of each key from its [low, high] to [-1, 1].

    A feature that never varies in the data (say, a contact force that stays zero) maps
    to 0 instead of dividing by zero, and back to its constant.
    """

    def __init__(self, low: dict[str, torch.Tensor], high: dict[str, torch.Tensor]) -> None:
        if set(low) != set(high):
            raise ValueError(f"low and high name different keys: {sorted(low)} vs {sorted(high)}")
        self.low = {k: v.float() for k, v in low.items()}
        self.high = {k: v.float() for k, v in high.items()}

    @classmethod
    def fit(cls, data: dict[str, torch.Tensor]) -> MinMaxNormalizer:
        """Statistics over every axis but the last of each array."""
        low, high = {}, {}
        for key, value in data.items():
            flat = torch.as_tensor(value).float().reshape(-1, value.shape[-1])
            low[key], high[key] = flat.min(dim=0).values, flat.max(dim=0).values
        return cls(low, high)

    def keys(self) -> list[str]:
        return sorted(self.low)

    def _centre_half(self, key: str, like: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        low = self.low[key].to(like.device)
        high = self.high[key].to(like.device)
        return (high + low) / 2, (high - low) / 2

    def normalize(self, key: str, x: torch.Tensor) -> torch.Tensor:
        centre, half = self._centre_half(key, x)
        return (x - centre) / torch.where(half < EPS, torch.ones_like(half), half)

    def unnormalize(self, key: str, x: torch.Tensor) -> torch.Tensor:
        """Back to data units; a constant feature comes back as its constant."""
        centre, half = self._centre_half(key, x)
        return x * half + centre

    def state_dict(self) -> dict[str, dict[str, torch.Tensor]]:
        return {"low": dict(self.low), "high": dict(self.high)}

    @classmethod
    def from_state_dict(cls, state: dict[str, dict[str, torch.Tensor]]) -> MinMaxNormalizer:
        return cls(state["low"], state["high"])
