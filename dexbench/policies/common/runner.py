"""A trained diffusion policy (DP or DP3) driving a batched env through the Policy API.

Each env keeps its own observation history and action queue (`ChunkedActor`); envs
whose queue ran out are planned for together, on the policy's device, with the EMA
weights. Sampling noise comes from a generator seeded with the env's seed, so the same
checkpoint, env seed and observations give the same actions.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import torch

from dexbench.policies.common.checkpoint import spec_of
from dexbench.policies.common.chunking import ChunkedActor
from dexbench.policies.common.diffusion import DiffusionPolicyModel
from dexbench.policies.common.normalizer import MinMaxNormalizer
from dexbench.policies.common.protocol import check_action_layout

ModelFactory = Callable[[dict[str, Any], dict[str, tuple[int, ...]], int], DiffusionPolicyModel]


def resolve_device(device: str | torch.device | None) -> torch.device:
    """`auto` (or None): CUDA when there is a GPU, else CPU."""
    if device is None or str(device) == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    device = torch.device(device)
    if device.type == "cuda" and not torch.cuda.is_available():
        raise ValueError("device=cuda but no CUDA GPU is visible; use device=cpu or auto")
    return device


class DiffusionChunkPolicy:
    def __init__(self, payload: dict[str, Any], make_model: ModelFactory, env,
                 device: str | torch.device | None = "auto") -> None:
        self.spec = spec_of(payload)
        check_action_layout(self.spec, env.embodiment.actuators)
        cfg = payload["config"]["policy"]
        self.groups = list(payload["groups"])
        shapes = {g: tuple(s) for g, s in payload["shapes"].items()}
        self.device = resolve_device(device)
        self.model = make_model(cfg, shapes, len(self.spec.action_layout))
        self.model.load_state_dict(payload["ema"])
        self.model.to(self.device).eval()
        self.normalizer = MinMaxNormalizer.from_state_dict(payload["normalizer"])
        self.env_device = env.device
        self.stacked = bool(env.history)  # env-side history: (N, k, ...); we keep our own
        self.actor = ChunkedActor(env.num_envs, int(cfg["n_obs_steps"]),
                                  int(cfg["n_action_steps"]), len(self.spec.action_layout),
                                  self.device)
        self.generator = torch.Generator(self.device).manual_seed(int(env.seed))

    def reset(self, env_ids: torch.Tensor | None = None) -> None:
        self.actor.reset(env_ids)

    def reads_next(self) -> torch.Tensor | None:
        """The envs whose next observation this policy will read (None: all, as with an
        env-side history, whose stacks need every frame)."""
        return None if self.stacked else self.actor.reads_next()

    def act(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        missing = [g for g in self.groups if g not in obs]
        if missing:
            raise ValueError(f"the policy needs observation groups {missing}; build the env "
                             f"with obs={self.spec.obs!r}")
        frame = {}
        for group in self.groups:
            value = obs[group][:, -1] if self.stacked else obs[group]
            frame[group] = self.normalizer.normalize(group, value.to(self.device).float())
        return self.actor.act(frame, self._plan).to(self.env_device)

    @torch.inference_mode()
    def _plan(self, windows: dict[str, torch.Tensor]) -> torch.Tensor:
        chunk = self.model.sample(windows, generator=self.generator)
        return self.normalizer.unnormalize("action", chunk)
