"""The training loop shared by DP and DP3: batches gathered on the device, AdamW with
cosine decay after warm-up, gradient clipping, EMA, per-epoch validation of the EMA
model, early stopping, and best/last checkpoints.

The whole dataset (normalized) lives on the training device and batches are gathered
by index, so no data-loader workers are needed: demonstrations are small.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from diffusers.optimization import get_cosine_schedule_with_warmup
from tqdm import tqdm

from dexbench.policies.common.demos import Demos, episode_frames, split_episodes, windows
from dexbench.policies.common.diffusion import DiffusionPolicyModel
from dexbench.policies.common.ema import EMA
from dexbench.policies.common.normalizer import MinMaxNormalizer
from dexbench.policies.common.run_log import RunLog


@dataclass(frozen=True)
class TrainSettings:
    epochs: int
    batch_size: int
    lr: float
    weight_decay: float
    betas: tuple[float, float]
    grad_clip: float
    warmup_steps: int
    ema_max_decay: float
    ema_power: float
    n_obs_steps: int
    horizon: int
    val_fraction: float = 0.1
    patience: int | None = None  # epochs without a better validation loss before stopping
    max_steps: int | None = None
    max_minutes: float | None = None
    save_every: int = 10  # epochs between checkpoint writes (and at the end)
    seed: int = 0
    amp: bool = True  # bfloat16 autocast on CUDA
    progress: bool = True


def fit_normalizer(demos: Demos) -> MinMaxNormalizer:
    return MinMaxNormalizer.fit({"action": demos.actions, **demos.obs})


class _Batches:
    """Normalized frames on the device and the index windows of every sample."""

    def __init__(self, demos: Demos, normalizer: MinMaxNormalizer, settings: TrainSettings,
                 device: torch.device) -> None:
        def put(key: str, value: np.ndarray) -> torch.Tensor:
            return normalizer.normalize(key, torch.from_numpy(value).to(device))

        self.obs = {g: put(g, v) for g, v in demos.obs.items()}
        self.actions = put("action", demos.actions)
        obs_idx, act_idx = windows(demos.episode_ends, settings.n_obs_steps, settings.horizon)
        self.obs_idx = torch.from_numpy(obs_idx).to(device)
        self.act_idx = torch.from_numpy(act_idx).to(device)
        train_eps, val_eps = split_episodes(demos.num_episodes, settings.val_fraction,
                                            settings.seed)
        self.train_eps, self.val_eps = train_eps.tolist(), val_eps.tolist()
        self.train = torch.from_numpy(episode_frames(demos.episode_ends, train_eps)).to(device)
        self.val = torch.from_numpy(episode_frames(demos.episode_ends, val_eps)).to(device)

    def get(self, ids: torch.Tensor) -> tuple[dict[str, torch.Tensor], torch.Tensor]:
        obs_rows = self.obs_idx[ids]
        return ({g: v[obs_rows] for g, v in self.obs.items()}, self.actions[self.act_idx[ids]])


def _copy_state(model: torch.nn.Module) -> dict[str, torch.Tensor]:
    """A copy that later updates do not touch, kept in host memory: a DP3-sized model's
    best snapshot (model and EMA, 2 GB) would otherwise hold GPU memory that trainings
    sharing one GPU need."""
    return {k: v.detach().to("cpu", copy=True) for k, v in model.state_dict().items()}


def _fast_cuda_kernels() -> None:
    """cuDNN's autotuned convolutions and TF32 float32 matmuls: with the fused AdamW, DP3's
    step (255 M parameters, batch 128) ran 1.7x faster on an H200 (`python bench.py train`
    measures it). GPU training is not bit-reproducible either way."""
    torch.backends.cudnn.benchmark = True
    torch.set_float32_matmul_precision("high")


def train_policy(model: DiffusionPolicyModel, demos: Demos, normalizer: MinMaxNormalizer,
                 settings: TrainSettings, device: torch.device, log: RunLog,
                 save: Callable[[str, dict[str, Any]], None]) -> dict[str, Any]:
    """Train `model` in place; `save(name, state)` writes a checkpoint of `state` (model,
    ema, normalizer, epoch, step, val_loss). Returns a summary of the run."""
    torch.manual_seed(settings.seed)
    model.to(device).train()
    data = _Batches(demos, normalizer, settings, device)
    if len(data.train) == 0:
        raise ValueError("no training frames: the dataset needs at least one episode")
    ema = EMA(model, settings.ema_max_decay, settings.ema_power)
    cuda = device.type == "cuda"
    if cuda:
        _fast_cuda_kernels()
    optimizer = torch.optim.AdamW(model.parameters(), lr=settings.lr, betas=settings.betas,
                                  weight_decay=settings.weight_decay, fused=cuda)
    per_epoch = math.ceil(len(data.train) / settings.batch_size)
    total = settings.epochs * per_epoch
    if settings.max_steps is not None:
        total = min(total, settings.max_steps)
    scheduler = get_cosine_schedule_with_warmup(optimizer, min(settings.warmup_steps, total // 10),
                                                total)
    amp = settings.amp and cuda
    shuffle = torch.Generator().manual_seed(settings.seed)
    started, step, epoch = time.perf_counter(), 0, 0
    best_loss, best_epoch, best = math.inf, -1, None
    stop_reason, val_loss = "epochs", None

    def snapshot(val_loss: float | None) -> dict[str, Any]:
        return {"model": _copy_state(model), "ema": _copy_state(ema.model),
                "normalizer": normalizer.state_dict(), "epoch": epoch, "step": step,
                "val_loss": val_loss}

    bar = tqdm(total=total, desc="train", unit="step", disable=not settings.progress)
    try:
        while step < total:
            epoch += 1
            losses = []
            order = data.train[torch.randperm(len(data.train), generator=shuffle).to(device)]
            for i in range(0, len(order), settings.batch_size):
                obs, actions = data.get(order[i:i + settings.batch_size])
                with torch.autocast(device.type, dtype=torch.bfloat16, enabled=amp):
                    loss = model.compute_loss(obs, actions)
                optimizer.zero_grad(set_to_none=True)
                loss.backward()
                torch.nn.utils.clip_grad_norm_(model.parameters(), settings.grad_clip)
                optimizer.step()
                scheduler.step()
                ema.update(model)
                step += 1
                losses.append(loss.detach())
                bar.update()
                if step >= total:
                    stop_reason = "max_steps" if settings.max_steps is not None and \
                        step >= settings.max_steps else "epochs"
                    break
            train_loss = float(torch.stack(losses).mean())
            val_loss = _validate(ema.model, data, settings, device, amp)
            row = {"epoch": epoch, "step": step, "train_loss": train_loss,
                   "val_loss": val_loss, "lr": scheduler.get_last_lr()[0],
                   "ema_decay": ema.decay(),
                   "elapsed_s": round(time.perf_counter() - started, 2)}
            log.epoch(row)
            bar.set_postfix(epoch=epoch, loss=f"{train_loss:.4f}",
                            val=f"{val_loss:.4f}" if val_loss is not None else "-")
            score = val_loss if val_loss is not None else train_loss
            if score < best_loss:
                best_loss, best_epoch, best = score, epoch, snapshot(val_loss)
            if epoch % settings.save_every == 0:
                save("best", best)
                save("last", snapshot(val_loss))
            if settings.patience is not None and epoch - best_epoch >= settings.patience:
                stop_reason = "early stop"
                break
            minutes = (time.perf_counter() - started) / 60
            if settings.max_minutes is not None and minutes >= settings.max_minutes:
                stop_reason = "time limit"
                break
    finally:
        bar.close()
        if best is not None:  # an interrupted run keeps what it learned
            save("best", best)
            save("last", snapshot(val_loss))
    return {"epochs": epoch, "steps": step, "best_epoch": best_epoch,
            "best_loss": best_loss, "stop_reason": stop_reason,
            "train_episodes": data.train_eps, "val_episodes": data.val_eps,
            "train_frames": len(data.train), "val_frames": len(data.val),
            "wall_time_s": round(time.perf_counter() - started, 2)}


@torch.no_grad()
def _validate(model: DiffusionPolicyModel, data: _Batches, settings: TrainSettings,
              device: torch.device, amp: bool) -> float | None:
    """Mean denoising loss of the EMA model on the validation episodes, with the same
    noise and diffusion steps every epoch so that epochs compare."""
    if len(data.val) == 0:
        return None
    generator = torch.Generator(device).manual_seed(settings.seed + 1)
    total, count = 0.0, 0
    for i in range(0, len(data.val), settings.batch_size):
        ids = data.val[i:i + settings.batch_size]
        obs, actions = data.get(ids)
        with torch.autocast(device.type, dtype=torch.bfloat16, enabled=amp):
            loss = model.compute_loss(obs, actions, generator=generator)
        total += float(loss) * len(ids)
        count += len(ids)
    return total / count
