"""`policy=openpi`: a pi0 / pi0.5 model behind an openpi policy server.

openpi serves a fine-tuned checkpoint with `scripts/serve_policy.py` on a websocket
(default port 8000). On connecting, the server sends its metadata; each request is one
observation dict packed with msgpack (NumPy arrays as `msgpack_numpy` lays them out),
and the answer holds `actions`, a chunk (H, action_dim) of absolute joint targets in the
embodiment's actuator order. A text frame instead of a binary one is the server's error.

The request: each camera of `cameras` under its key of `image_keys` (uint8, H x W x 3,
resized with padding to `image_size`), the robot joint positions under `state_key`
(unless null) and the task's language instruction under `prompt_key`. Keys follow the
server's input transform; the defaults match openpi's single-arm examples.
"""

from __future__ import annotations

import contextlib
import weakref
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch
from websockets.exceptions import InvalidHandshake, InvalidURI, WebSocketException
from websockets.sync.client import ClientConnection, connect

from dexbench.envs.dex_env import DexEnv
from dexbench.policies.common.protocol import PolicySpec
from dexbench.policies.vla_adapters import msgpack_numpy
from dexbench.policies.vla_adapters.chunks import ChunkQueuePolicy, RemotePolicyError
from dexbench.policies.vla_adapters.images import resize_with_pad

# The settings of conf/policy/openpi.yaml (where their defaults and meanings live).
SETTINGS = ("host", "port", "api_key", "cameras", "image_keys", "image_size", "state_key",
            "prompt_key", "prompt", "actions_key", "replan_steps", "timeout_s")


def settings(options: Mapping[str, Any]) -> dict[str, Any]:
    """The adapter's settings from `options` (conf/policy/openpi.yaml), checked before any
    env is built."""
    unknown = sorted(set(options) - set(SETTINGS))
    missing = [k for k in SETTINGS if k not in options]
    if unknown or missing:
        raise ValueError(f"policy=openpi settings: unknown {unknown}, missing {missing}; "
                         f"it takes {', '.join(SETTINGS)} (conf/policy/openpi.yaml)")
    s = dict(options)
    cameras, keys = list(s["cameras"] or []), list(s["image_keys"] or [])
    if not cameras or len(cameras) != len(keys):
        raise ValueError(f"policy.cameras ({len(cameras)}) and policy.image_keys "
                         f"({len(keys)}) must name the same number of images, at least one")
    if int(s["image_size"]) < 1 or int(s["replan_steps"]) < 1 or float(s["timeout_s"]) <= 0:
        raise ValueError("policy.image_size and policy.replan_steps must be >= 1 and "
                         "policy.timeout_s > 0")
    return {**s, "cameras": cameras, "image_keys": keys}


def spec(checkpoint: str | None, options: Mapping[str, Any]) -> PolicySpec:
    if checkpoint is not None:
        raise ValueError("policy=openpi takes no checkpoint: the server loads it; point "
                         "policy.host and policy.port at the server")
    s = settings(options)
    return PolicySpec(obs=("proprio", "rgb"), cameras=tuple(s["cameras"]))


def server_uri(s: Mapping[str, Any]) -> str:
    host = str(s["host"])
    uri = host if host.startswith(("ws://", "wss://")) else f"ws://{host}"
    return uri if s["port"] is None else f"{uri}:{int(s['port'])}"


class OpenpiClient:
    """One websocket connection to an openpi policy server."""

    def __init__(self, uri: str, api_key: str | None, timeout_s: float) -> None:
        headers = {"Authorization": f"Api-Key {api_key}"} if api_key else None
        self.uri, self._timeout = uri, timeout_s
        # Open for the client's lifetime, closed when the client is collected.
        stack = contextlib.ExitStack()
        try:
            self._ws: ClientConnection = stack.enter_context(connect(
                uri, compression=None, max_size=None, additional_headers=headers,
                open_timeout=timeout_s))
            self.metadata = msgpack_numpy.unpackb(self._ws.recv(timeout=timeout_s))
        except (OSError, TimeoutError, InvalidURI, InvalidHandshake) as err:
            stack.close()
            raise RemotePolicyError(
                f"no openpi policy server answered at {uri} ({err}); start one (openpi: "
                "scripts/serve_policy.py) or set policy.host / policy.port") from None
        weakref.finalize(self, stack.close)

    def infer(self, request: dict) -> dict:
        """Send one observation; the server's answer (a dict holding the action chunk)."""
        try:
            self._ws.send(msgpack_numpy.packb(request))
            reply = self._ws.recv(timeout=self._timeout)
        except (TimeoutError, WebSocketException, OSError) as err:
            raise RemotePolicyError(f"the openpi server at {self.uri} stopped answering "
                                    f"({err or type(err).__name__})") from None
        if isinstance(reply, str):
            raise RemotePolicyError(f"the openpi server at {self.uri} failed:\n{reply}")
        return msgpack_numpy.unpackb(reply)


def request_builder(env: DexEnv, s: Mapping[str, Any]):
    """Per-env request dicts from the batched observations, in openpi's layout."""
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


def build(checkpoint: str | None, env: DexEnv, device: torch.device | str,
          options: Mapping[str, Any]) -> ChunkQueuePolicy:
    spec(checkpoint, options)
    s = settings(options)
    client = OpenpiClient(server_uri(s), s["api_key"], float(s["timeout_s"]))
    key = str(s["actions_key"])

    def query(request: dict) -> np.ndarray:
        reply = client.infer(request)
        if not isinstance(reply, dict) or key not in reply:
            got = sorted(reply) if isinstance(reply, dict) else type(reply).__name__
            raise RemotePolicyError(f"the openpi server's answer has no {key!r} "
                                    f"(got {got}); set policy.actions_key")
        return reply[key]

    return ChunkQueuePolicy(
        PolicySpec(obs=("proprio", "rgb"), task=env.task.name,
                   action_layout=tuple(env.embodiment.actuators),
                   cameras=tuple(s["cameras"])),
        env.num_envs, len(env.embodiment.actuators), request_builder(env, s), query,
        int(s["replan_steps"]))
