"""A conditional diffusion model over action chunks: noise schedule, loss and sampling.

The network is ours (`ConditionalUnet1D` plus a per-policy observation encoder);
`diffusers` supplies only the noise schedules (DDPM for DP, DDIM for DP3). Everything
here works on normalized actions in [-1, 1].
"""

from __future__ import annotations

from typing import Any

import torch
from diffusers import DDIMScheduler, DDPMScheduler
from torch import nn
from torch.nn import functional as F

from dexbench.policies.common.unet import ConditionalUnet1D

SCHEDULERS = {"ddpm": DDPMScheduler, "ddim": DDIMScheduler}


def make_scheduler(cfg: dict[str, Any]) -> DDPMScheduler | DDIMScheduler:
    """`cfg`: scheduler (ddpm|ddim), num_train_timesteps, beta_schedule, prediction_type,
    clip_sample."""
    kind = cfg["scheduler"]
    if kind not in SCHEDULERS:
        raise ValueError(f"unknown noise scheduler {kind!r}; choose one of {sorted(SCHEDULERS)}")
    kwargs = dict(num_train_timesteps=int(cfg["num_train_timesteps"]),
                  beta_schedule=cfg["beta_schedule"], prediction_type=cfg["prediction_type"],
                  clip_sample=bool(cfg["clip_sample"]))
    if kind == "ddim":
        kwargs["set_alpha_to_one"] = True
    return SCHEDULERS[kind](**kwargs)


class DiffusionPolicyModel(nn.Module):
    """Observation encoder + FiLM U-Net denoiser over (B, horizon, action_dim) chunks.

    `encoder` maps a dict of normalized observation windows (B, To, ...) to (B, cond_dim).
    """

    def __init__(self, encoder: nn.Module, cond_dim: int, action_dim: int, horizon: int,
                 unet: dict[str, Any], noise: dict[str, Any]) -> None:
        super().__init__()
        self.encoder = encoder
        self.unet = ConditionalUnet1D(action_dim, cond_dim, **unet)
        self.action_dim, self.horizon = action_dim, horizon
        self.scheduler = make_scheduler(noise)
        self.num_inference_steps = int(noise["num_inference_steps"])
        self.prediction_type = noise["prediction_type"]

    def compute_loss(self, obs: dict[str, torch.Tensor], actions: torch.Tensor,
                     generator: torch.Generator | None = None) -> torch.Tensor:
        """Denoising loss of normalized `actions` (B, horizon, A) given `obs` windows."""
        cond = self.encoder(obs)
        b = actions.shape[0]
        noise = torch.randn(actions.shape, device=actions.device, generator=generator)
        steps = torch.randint(0, self.scheduler.config.num_train_timesteps, (b,),
                              device=actions.device, generator=generator)
        noisy = self.scheduler.add_noise(actions, noise, steps)
        pred = self.unet(noisy, steps, cond)
        target = noise if self.prediction_type == "epsilon" else actions
        return F.mse_loss(pred, target)

    @torch.no_grad()
    def sample(self, obs: dict[str, torch.Tensor],
               generator: torch.Generator | None = None) -> torch.Tensor:
        """Normalized action chunks (B, horizon, A) by iterative denoising."""
        cond = self.encoder(obs)
        b = cond.shape[0]
        x = torch.randn((b, self.horizon, self.action_dim), device=cond.device,
                        generator=generator)
        self.scheduler.set_timesteps(self.num_inference_steps, device=cond.device)
        for t in self.scheduler.timesteps:
            out = self.unet(x, t, cond)
            x = self.scheduler.step(out, t, x, generator=generator).prev_sample
        return x
