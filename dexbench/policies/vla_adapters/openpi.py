"""`policy=openpi`: a pi0 / pi0.5 model behind an openpi policy server.

openpi serves a fine-tuned checkpoint with `scripts/serve_policy.py` on a websocket
(default port 8000). On connecting, the server sends its metadata; each request is one
observation dict packed with msgpack (NumPy arrays as openpi-client's `msgpack_numpy`
lays them out), and the answer holds `actions`, a chunk (H, action_dim) of absolute
joint targets in the embodiment's actuator order. A text frame instead of a binary one
is the server's error (its traceback); the server then closes the connection.

The request is `served.request_builder`'s; the default keys match openpi's single-arm
examples (follow your server's input transform).
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
from dexbench.policies.vla_adapters.served import COMMON, chunk_policy, served_spec, settings

KIND = "openpi"
SETTINGS = (*COMMON, "api_key", "actions_key")


def spec(checkpoint: str | None, options: Mapping[str, Any]) -> PolicySpec:
    return served_spec(settings(KIND, checkpoint, options, SETTINGS))


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


def build(checkpoint: str | None, env: DexEnv, device: torch.device | str,
          options: Mapping[str, Any]) -> ChunkQueuePolicy:
    s = settings(KIND, checkpoint, options, SETTINGS)
    client = OpenpiClient(server_uri(s), s["api_key"], float(s["timeout_s"]))
    key = str(s["actions_key"])

    def query(request: dict) -> np.ndarray:
        reply = client.infer(request)
        if not isinstance(reply, dict) or key not in reply:
            got = sorted(reply) if isinstance(reply, dict) else type(reply).__name__
            raise RemotePolicyError(f"the openpi server's answer has no {key!r} "
                                    f"(got {got}); set policy.actions_key")
        return reply[key]

    return chunk_policy(env, s, query)
