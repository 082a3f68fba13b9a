"""A batched policy over a model that answers one observation at a time with a chunk.

VLA servers take one observation and return an action chunk (H, action_dim). Each env
keeps a queue: when it runs dry, that env's observation is sent and the first
`replan_steps` actions of the answer are queued; every control step each env plays its
next queued action. An env that resets drops its queue, so a new episode starts with a
fresh query.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

import numpy as np
import torch

from dexbench.policies.common.protocol import PolicySpec

# Builds the requests of the envs `ids` from the batched observations.
RequestBuilder = Callable[[dict[str, torch.Tensor], list[int]], list[dict]]
# Sends one request, returns its action chunk (H, action_dim).
ChunkQuery = Callable[[dict], np.ndarray]


class RemotePolicyError(RuntimeError):
    """A model server could not be reached or answered with something unusable."""


class ChunkQueuePolicy:
    """Per-env action queues filled from a chunk-returning model."""

    def __init__(self, spec: PolicySpec, num_envs: int, action_dim: int,
                 build_requests: RequestBuilder, query: ChunkQuery,
                 replan_steps: int) -> None:
        self.spec = spec
        self.queries = 0  # requests sent so far
        self._action_dim = action_dim
        self._build = build_requests
        self._query = query
        self._replan = replan_steps
        self._queues: list[deque[np.ndarray]] = [deque() for _ in range(num_envs)]

    def reset(self, env_ids: torch.Tensor) -> None:
        for i in env_ids.tolist():
            self._queues[i].clear()

    def _chunk(self, request: dict) -> np.ndarray:
        chunk = np.asarray(self._query(request), dtype=np.float32)
        if chunk.ndim == 1:
            chunk = chunk[None]
        if chunk.ndim != 2 or chunk.shape[1] != self._action_dim or not len(chunk):
            raise RemotePolicyError(
                f"the model answered actions of shape {tuple(chunk.shape)}; this env takes "
                f"(steps, {self._action_dim}) absolute joint targets in the embodiment's "
                "actuator order (python -m dexbench inspect shows it)")
        if not np.isfinite(chunk).all():
            raise RemotePolicyError("the model answered non-finite actions")
        return chunk

    def act(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        empty = [i for i, q in enumerate(self._queues) if not q]
        if empty:
            for i, request in zip(empty, self._build(obs, empty), strict=True):
                self._queues[i].extend(self._chunk(request)[:self._replan])
                self.queries += 1
        actions = np.stack([q.popleft() for q in self._queues])
        device = next(iter(obs.values())).device
        return torch.as_tensor(actions, device=device)
