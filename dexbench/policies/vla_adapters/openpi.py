"""`policy=openpi`: a pi0 / pi0.5 model behind an openpi policy server.

openpi serves a fine-tuned checkpoint with `scripts/serve_policy.py` on a websocket
(default port 8000). On connecting, the server sends its metadata; each request is one
observation dict packed with msgpack (NumPy arrays as openpi-client's `msgpack_numpy`
lays them out), and the answer holds `actions`, a chunk (H, action_dim) of absolute
joint targets in the embodiment's actuator order. A text frame instead of a binary one
is the server's error (its traceback); the server then closes the connection.

The request is `served.request_builder`'s; the default keys match openpi's single-arm
examples (follow your server's input transform).

A dexbench server (`python -m dexbench serve`, schema in `dexbench/policies/serving.py`)
says in its metadata which observation groups it reads; against one, the env is built
with the checkpoint's observations, each env gets its own connection (the server keeps
one history per connection) and sends those groups instead of images and prompt: every
control step's frame (`observe_only` between queries when the model reads several
frames, as it was trained on consecutive steps), and `reset` when its episode restarts.
"""

from __future__ import annotations

import contextlib
import weakref
from collections.abc import Mapping
from dataclasses import replace
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
PROBE_S = 10.0  # longest wait for the metadata when reading the spec
ENV_KEY = "__env__"  # routes a request to its env's connection; never sent


def spec(checkpoint: str | None, options: Mapping[str, Any]) -> PolicySpec:
    """A dexbench server's checkpoint spec (its metadata), else images and joint positions
    (also when no server answers yet: `build` then says so)."""
    s = settings(KIND, checkpoint, options, SETTINGS)
    try:
        client = OpenpiClient(server_uri(s), s["api_key"], min(float(s["timeout_s"]), PROBE_S))
    except RemotePolicyError:
        return served_spec(s)
    client.close()
    return groups_spec(client.metadata) if asks_for_groups(client.metadata) else served_spec(s)


def asks_for_groups(metadata: Any) -> bool:
    """Whether the server reads observation groups by name (a dexbench server)."""
    return (isinstance(metadata, dict) and isinstance(metadata.get("groups"), list)
            and all(k in metadata for k in ("obs", "n_obs_steps", "action_layout")))


def groups_spec(metadata: dict) -> PolicySpec:
    obs = metadata["obs"]
    return PolicySpec(obs=obs if isinstance(obs, str) else tuple(obs),
                      task=metadata.get("task"), embodiment=metadata.get("embodiment"),
                      action_layout=tuple(metadata["action_layout"]))


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
        self.close = weakref.finalize(self, stack.close)  # also when collected

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


def actions_of(reply: Any, key: str) -> np.ndarray:
    if not isinstance(reply, dict) or key not in reply:
        got = sorted(reply) if isinstance(reply, dict) else type(reply).__name__
        raise RemotePolicyError(f"the openpi server's answer has no {key!r} "
                                f"(got {got}); set policy.actions_key")
    return reply[key]


class GroupsChunkPolicy(ChunkQueuePolicy):
    """The chunk policy against a dexbench server: one connection per env, the groups
    its metadata names, every step's frame, a reset per restarted episode."""

    def __init__(self, env: DexEnv, s: Mapping[str, Any], clients: list[OpenpiClient]) -> None:
        metadata = clients[0].metadata
        self._clients, self._key = clients, str(s["actions_key"])
        self._groups = [str(g) for g in metadata["groups"]]
        self._stacked = bool(env.history)  # env-side history (N, k, ...): send the last
        self._observe = int(metadata["n_obs_steps"]) > 1
        super().__init__(replace(groups_spec(metadata), task=env.task.name), env.num_envs,
                         len(env.embodiment.actuators), self._requests, self._query,
                         int(s["replan_steps"]))

    def _frames(self, obs: dict[str, torch.Tensor], ids: list[int]) -> list[dict]:
        missing = [g for g in self._groups if g not in obs]
        if missing:
            raise RemotePolicyError(f"the server reads observation groups {missing} that "
                                    "this env does not give")
        index = torch.as_tensor(ids, dtype=torch.long, device=obs[self._groups[0]].device)
        arrays = {g: (obs[g][:, -1] if self._stacked else obs[g])[index].cpu().numpy()
                  for g in self._groups}
        return [{g: a[row] for g, a in arrays.items()} for row in range(len(ids))]

    def _requests(self, obs: dict[str, torch.Tensor], ids: list[int]) -> list[dict]:
        return [{**frame, ENV_KEY: i}
                for frame, i in zip(self._frames(obs, ids), ids, strict=True)]

    def _query(self, request: dict) -> np.ndarray:
        client = self._clients[request.pop(ENV_KEY)]
        return actions_of(client.infer(request), self._key)

    def reset(self, env_ids: torch.Tensor) -> None:
        super().reset(env_ids)
        for i in env_ids.tolist():
            self._clients[i].infer({"reset": True})

    def act(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        if self._observe:
            playing = [i for i, q in enumerate(self._queues) if q]
            for i, frame in zip(playing, self._frames(obs, playing), strict=True):
                self._clients[i].infer({**frame, "observe_only": True})
        return super().act(obs)


def build(checkpoint: str | None, env: DexEnv, device: torch.device | str,
          options: Mapping[str, Any]) -> ChunkQueuePolicy:
    s = settings(KIND, checkpoint, options, SETTINGS)
    client = OpenpiClient(server_uri(s), s["api_key"], float(s["timeout_s"]))
    if asks_for_groups(client.metadata):
        clients = [client, *(OpenpiClient(client.uri, s["api_key"], float(s["timeout_s"]))
                             for _ in range(env.num_envs - 1))]
        return GroupsChunkPolicy(env, s, clients)
    key = str(s["actions_key"])
    return chunk_policy(env, s, lambda request: actions_of(client.infer(request), key))
