"""Exponential moving average of model weights, the copy that is evaluated.

The decay warms up as 1 - (1 + step)^-power (capped at `max_decay`), as in Diffusion
Policy, so early averages are not dominated by the random initialization.
"""

from __future__ import annotations

import copy

import torch
from torch import nn


class EMA:
    def __init__(self, model: nn.Module, max_decay: float = 0.9999, power: float = 0.75,
                 min_decay: float = 0.0) -> None:
        if not 0.0 <= min_decay <= max_decay < 1.0:
            raise ValueError(f"need 0 <= min_decay <= max_decay < 1, got {min_decay}, "
                             f"{max_decay}")
        self.model = copy.deepcopy(model).eval().requires_grad_(False)
        self.max_decay, self.power, self.min_decay = max_decay, power, min_decay
        self.step = 0

    def decay(self) -> float:
        value = 1.0 - (1.0 + self.step) ** -self.power
        return min(self.max_decay, max(self.min_decay, value))

    @torch.no_grad()
    def update(self, model: nn.Module) -> None:
        weight = 1.0 - self.decay()
        ema_params = list(self.model.parameters())
        params = [p.detach() for p in model.parameters()]
        torch._foreach_lerp_(ema_params, params, weight)
        for ema_buf, buf in zip(self.model.buffers(), model.buffers(), strict=True):
            ema_buf.copy_(buf)
        self.step += 1
