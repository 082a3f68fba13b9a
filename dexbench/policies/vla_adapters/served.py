"""What every adapter of a model served elsewhere shares: its settings, its spec, the
per-env requests (camera images, joint positions, instruction) and the chunk policy.

A request holds each camera of `cameras` under its key of `image_keys` (uint8,
H x W x 3, resized with padding to `image_size`), the robot joint positions under
`state_key` (unless null) and the task's language instruction (or `prompt`) under
`prompt_key`. The keys follow the server's input format; each kind's YAML defaults
match its reference examples.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.policies.common.protocol import PolicySpec
from dexbench.policies.vla_adapters.chunks import ChunkQuery, ChunkQueuePolicy, RequestBuilder
from dexbench.policies.vla_adapters.images import resize_with_pad

OBS = ("proprio", "rgb")
# Settings every served kind has (its conf/policy/<kind>.yaml gives defaults and meaning).
COMMON = ("host", "port", "cameras", "image_keys", "image_size", "state_key", "prompt_key",
          "prompt", "replan_steps", "timeout_s")
# Settings that say where the server is, not what it sees: a resumed evaluation may
# change them (a restarted server), but none of the others.
TRANSPORT = ("host", "port", "api_key", "timeout_s")


def settings(kind: str, checkpoint: str | None, options: Mapping[str, Any],
             names: tuple[str, ...]) -> dict[str, Any]:
    """`options` checked against the kind's setting `names`, before any env is built (a
    served kind loads no checkpoint)."""
    if checkpoint is not None:
        raise ValueError(f"policy={kind} takes no checkpoint: the server loads it; point "
                         "policy.host and policy.port at the server")
    unknown = sorted(set(options) - set(names))
    missing = [k for k in names if k not in options]
    if unknown or missing:
        raise ValueError(f"policy={kind} settings: unknown {unknown}, missing {missing}; "
                         f"it takes {', '.join(names)} (conf/policy/{kind}.yaml)")
    s = dict(options)
    cameras, keys = list(s["cameras"] or []), list(s["image_keys"] or [])
    if not cameras or len(cameras) != len(keys):
        raise ValueError(f"policy.cameras ({len(cameras)}) and policy.image_keys "
                         f"({len(keys)}) must name the same number of images, at least one")
    if int(s["image_size"]) < 1 or int(s["replan_steps"]) < 1 or float(s["timeout_s"]) <= 0:
        raise ValueError("policy.image_size and policy.replan_steps must be >= 1 and "
                         "policy.timeout_s > 0")
    return {**s, "cameras": cameras, "image_keys": keys}


def served_spec(s: Mapping[str, Any]) -> PolicySpec:
    """What any served kind needs from the env: joint positions and its cameras' images."""
    return PolicySpec(obs=OBS, cameras=tuple(s["cameras"]))


def request_builder(env: DexEnv, s: Mapping[str, Any]) -> RequestBuilder:
    """Per-env request dicts from the batched observations."""
    prompt = str(s["prompt"] or env.task.instruction)
    pairs = list(zip(s["image_keys"], s["cameras"], strict=True))

    def build(obs: dict[str, torch.Tensor], ids: list[int]) -> list[dict]:
        index = torch.as_tensor(ids, device=obs["proprio"].device)
        images = {key: resize_with_pad(obs[f"rgb/{camera}"][index], int(s["image_size"]))
                  .cpu().numpy() for key, camera in pairs}
        state = obs["proprio"][index].float().cpu().numpy()
        requests = []
        for row in range(len(ids)):
            request: dict[str, Any] = {key: images[key][row] for key, _ in pairs}
            if s["state_key"]:
                request[str(s["state_key"])] = state[row]
            request[str(s["prompt_key"])] = prompt
            requests.append(request)
        return requests

    return build


def chunk_policy(env: DexEnv, s: Mapping[str, Any], query: ChunkQuery) -> ChunkQueuePolicy:
    """The batched policy playing the chunks `query` returns for `env`'s requests."""
    spec = replace(served_spec(s), task=env.task.name,
                   action_layout=tuple(env.embodiment.actuators))
    return ChunkQueuePolicy(spec, env.num_envs, len(env.embodiment.actuators),
                            request_builder(env, s), query, int(s["replan_steps"]))
