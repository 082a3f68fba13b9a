"""`policy=openvla_oft`: an OpenVLA-OFT model behind its REST deploy server.

OpenVLA-OFT serves a fine-tuned checkpoint with `vla-scripts/deploy.py` (FastAPI, default
port 8777): each request is one JSON observation posted to `/act`, NumPy arrays encoded
as `json_numpy` lays them out, and the answer is the action chunk (a list of
`action_dim` vectors, 8 with the paper's L1-regression head) as absolute joint targets
in the embodiment's actuator order. The server answers the string "error" (and logs the
traceback) when a request fails.

The request is `served.request_builder`'s; the default keys (`full_image`,
`wrist_image`, `state`, `instruction`) are those the deploy server reads.
"""

from __future__ import annotations

import urllib.error
import urllib.request
from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.policies.common.protocol import PolicySpec
from dexbench.policies.vla_adapters import json_numpy
from dexbench.policies.vla_adapters.chunks import ChunkQueuePolicy, RemotePolicyError
from dexbench.policies.vla_adapters.served import COMMON, chunk_policy, served_spec, settings

KIND = "openvla_oft"
SETTINGS = (*COMMON, "route")


def spec(checkpoint: str | None, options: Mapping[str, Any]) -> PolicySpec:
    return served_spec(settings(KIND, checkpoint, options, SETTINGS))


def server_url(s: Mapping[str, Any]) -> str:
    host = str(s["host"])
    base = host if host.startswith(("http://", "https://")) else f"http://{host}"
    if s["port"] is not None:
        base = f"{base}:{int(s['port'])}"
    return f"{base}/{str(s['route']).lstrip('/')}"


def post(url: str, request: dict, timeout_s: float) -> np.ndarray:
    """POST one observation; the action chunk the server answers."""
    body = json_numpy.dumps(request).encode()
    message = urllib.request.Request(url, data=body, method="POST",
                                     headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(message, timeout=timeout_s) as response:
            reply = json_numpy.loads(response.read())
    except urllib.error.HTTPError as err:
        raise RemotePolicyError(f"the OpenVLA-OFT server at {url} answered HTTP {err.code} "
                                f"({err.reason})") from None
    except (urllib.error.URLError, OSError) as err:
        raise RemotePolicyError(
            f"no OpenVLA-OFT server answered at {url} ({getattr(err, 'reason', err)}); start "
            "one (openvla-oft: vla-scripts/deploy.py) or set policy.host / policy.port"
        ) from None
    if isinstance(reply, str) and reply != "error":
        reply = json_numpy.loads(reply)  # the server's double-encoded form
    if isinstance(reply, str):
        raise RemotePolicyError(f"the OpenVLA-OFT server at {url} failed on the request "
                                "(its log has the traceback)")
    return np.asarray(reply, dtype=np.float32)


def build(checkpoint: str | None, env: DexEnv, device: torch.device | str,
          options: Mapping[str, Any]) -> ChunkQueuePolicy:
    s = settings(KIND, checkpoint, options, SETTINGS)
    url, timeout_s = server_url(s), float(s["timeout_s"])
    return chunk_policy(env, s, lambda request: post(url, request, timeout_s))
