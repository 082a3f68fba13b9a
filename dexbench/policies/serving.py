"""Our checkpointed policies (dp, dp3, rl) behind openpi's websocket policy protocol.

Any openpi client (`openpi_client.WebsocketClientPolicy`, or `policy=openpi` here) talks
to `python -m dexbench serve policy=<kind> checkpoint=<path>`. Frames are msgpack with
NumPy arrays in `openpi_client.msgpack_numpy`'s layout.

On connect the server sends its metadata frame (a map):

    server        "dexbench"
    protocol      1 (this schema's version)
    kind          "dp" | "dp3" | "rl"
    task, embodiment   what the checkpoint was trained on
    obs           the env's observation preset (or group list) the policy was trained with
    groups        [name, ...]: the observation groups every request carries
    shapes        {name: [dim, ...]}: one frame of each group, no batch or time axis
    dtypes        {name: "float32"}: what the model reads (other real dtypes are cast)
    n_obs_steps   frames of history the model conditions on
    chunk_length  actions in each answer
    action_dim    actions' width; action_layout: the actuator names, in action order
    actions_key   "actions"

(dp / dp3: the checkpoint's groups, n_obs_steps and n_action_steps; rl: its actor's
groups plus `policy`, the joint targets applied last, which its delta actions start
from, with n_obs_steps = chunk_length = 1.)

Requests (each gets exactly one answer frame):

- an observation: `{group: array of shapes[group], ...}` for every group (other keys,
  such as openpi's `prompt`, are ignored). The frame is appended to this connection's
  history (the first frame after a connect or reset fills the whole window, as in
  training) and the answer is `{"actions": float32 (chunk_length, action_dim)}`,
  absolute joint targets planned from the last `n_obs_steps` frames, to be played from
  this control step on.
- the same with `"observe_only": true`: the frame only joins the history (answer
  `{"observed": true}`). The model was trained on consecutive control steps, so a client
  that plays several actions of a chunk sends the frames of those steps this way when
  `n_obs_steps` > 1.
- `{"reset": true}` (optionally `"seed": int`): forget this connection's history, and
  seed its sampling noise again (with `seed`, else the server's); answer
  `{"reset": true}`. Send it when the episode starts over.

Each connection has its own history and noise generator, so several clients (or the
envs of one batched client, one connection each) run side by side. A malformed request
is answered with a text frame `error: ...` (openpi clients raise it) and the connection
and its history stay as they were; an unexpected failure sends the traceback as a text
frame and closes that connection with 1011, as openpi's server does. The server serves
on either way.
"""

from __future__ import annotations

import json
import logging
import threading
import traceback
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np
import torch
from websockets.exceptions import ConnectionClosed
from websockets.frames import CloseCode
from websockets.sync.server import Server, ServerConnection, serve

from dexbench.policies.common.checkpoint import load_checkpoint
from dexbench.policies.common.chunking import ObsWindow
from dexbench.policies.common.normalizer import MinMaxNormalizer
from dexbench.policies.common.runner import resolve_device
from dexbench.policies.registry import KINDS, SERVED, policy_module
from dexbench.policies.vla_adapters import msgpack_numpy

SERVABLE = ("dp", "dp3", "rl")
PROTOCOL = 1
ACTIONS, RESET, OBSERVE_ONLY, SEED = "actions", "reset", "observe_only", "seed"
log = logging.getLogger(__name__)


class RequestError(ValueError):
    """A request that does not follow the schema of the metadata frame."""


class Session(Protocol):
    """One connection's state."""

    def reset(self, seed: int) -> None: ...

    def step(self, frame: dict[str, np.ndarray], plan: bool) -> np.ndarray | None:
        """Take one frame; the chunk (chunk_length, action_dim) when `plan`."""


def unservable(kind: str) -> str | None:
    """Why `kind` cannot be served, or None."""
    if kind == "expert":
        return ("policy=expert is scripted from the simulator's state, which no client "
                "can send; serve a trained checkpoint (policy=dp, dp3 or rl)")
    if kind in SERVED or kind == "lerobot":
        return (f"policy={kind} is not a dexbench checkpoint; serve one of "
                f"{', '.join(SERVABLE)}")
    if kind not in KINDS:
        return f"unknown policy {kind!r}; serve one of {', '.join(SERVABLE)}"
    return None


class DiffusionServed:
    """A DP / DP3 checkpoint's EMA model; sessions keep history and noise per client."""

    def __init__(self, kind: str, checkpoint: str, device: torch.device) -> None:
        payload = load_checkpoint(checkpoint, kind)
        cfg = payload["config"]["policy"]
        self.groups = list(payload["groups"])
        self.shapes = {g: tuple(int(d) for d in payload["shapes"][g]) for g in self.groups}
        layout = list(payload["action_layout"])
        self.device = device
        self.model = policy_module(kind).make_model(cfg, self.shapes, len(layout))
        self.model.load_state_dict(payload["ema"])
        self.model.to(device).eval()
        self.normalizer = MinMaxNormalizer.from_state_dict(payload["normalizer"])
        self.n_obs_steps, self.n_action_steps = int(cfg["n_obs_steps"]), int(cfg["n_action_steps"])
        obs = payload["obs"]
        self.metadata = _metadata(kind, payload["task"], payload["embodiment"],
                                  obs if isinstance(obs, str) else list(obs), self.shapes,
                                  self.n_obs_steps, self.n_action_steps, layout)
        self.lock = threading.Lock()  # one model, planned for one client at a time

    def session(self, seed: int) -> DiffusionSession:
        return DiffusionSession(self, seed)


class DiffusionSession:
    def __init__(self, served: DiffusionServed, seed: int) -> None:
        self.served = served
        self.window = ObsWindow(1, served.n_obs_steps, served.device)
        self.generator = torch.Generator(served.device)
        self.reset(seed)

    def reset(self, seed: int) -> None:
        self.window.reset()
        self.generator.manual_seed(seed)

    def step(self, frame: dict[str, np.ndarray], plan: bool) -> np.ndarray | None:
        s = self.served
        normalized = {g: s.normalizer.normalize(
            g, torch.as_tensor(frame[g], dtype=torch.float32, device=s.device)[None])
            for g in s.groups}
        windows = self.window.push(normalized)
        if not plan:
            return None
        with s.lock, torch.inference_mode():
            chunk = s.model.sample(windows, generator=self.generator)
            chunk = s.normalizer.unnormalize("action", chunk)
        return chunk[0, :s.n_action_steps].float().cpu().numpy()


class RlServed:
    """A PPO actor (run deterministically): stateless, one action per answer. Its action
    map needs the env's actuator ranges, so one env of the run's task is built (never
    stepped)."""

    def __init__(self, checkpoint: str, device: torch.device) -> None:
        from dexbench.policies import rl
        from dexbench.tasks.registry import make_env

        model_path, meta = rl.resolve(checkpoint)
        groups = sorted({*meta["actor_groups"], "policy"})
        env = make_env(task=meta["task"], embodiment=meta["embodiment"], obs=groups,
                       num_envs=1, nthread=1)
        obs = env.reset()
        shapes = {g: tuple(obs[g].shape[1:]) for g in groups}
        self.policy = rl.RlPolicy(model_path, meta, env, device)
        self.groups = groups
        self.metadata = _metadata("rl", meta["task"], meta["embodiment"], groups, shapes, 1,
                                  1, list(meta["actuators"]))
        self.lock = threading.Lock()

    def session(self, seed: int) -> RlSession:
        return RlSession(self)


class RlSession:
    def __init__(self, served: RlServed) -> None:
        self.served = served

    def reset(self, seed: int) -> None:
        """Stateless: the last targets come with each request (`policy` group)."""

    def step(self, frame: dict[str, np.ndarray], plan: bool) -> np.ndarray | None:
        if not plan:
            return None
        obs = {g: torch.as_tensor(frame[g], dtype=torch.float32)[None]
               for g in self.served.groups}
        with self.served.lock:
            action = self.served.policy.act(obs)
        return action.float().cpu().numpy()


Served = DiffusionServed | RlServed


def _metadata(kind: str, task: str, embodiment: str, obs: str | list[str],
              shapes: Mapping[str, tuple[int, ...]], n_obs_steps: int, chunk_length: int,
              layout: list[str]) -> dict[str, Any]:
    return {"server": "dexbench", "protocol": PROTOCOL, "kind": kind, "task": task,
            "embodiment": embodiment, "obs": obs, "groups": list(shapes),
            "shapes": {g: list(s) for g, s in shapes.items()},
            "dtypes": dict.fromkeys(shapes, "float32"), "n_obs_steps": n_obs_steps,
            "chunk_length": chunk_length, "action_dim": len(layout),
            "action_layout": layout, "actions_key": ACTIONS}


def load_served(kind: str, checkpoint: str, device: str = "auto") -> Served:
    """The servable model of a checkpoint, or a ValueError saying why not."""
    why = unservable(kind)
    if why:
        raise ValueError(why)
    if kind == "rl":
        return RlServed(checkpoint, resolve_device(device))
    return DiffusionServed(kind, checkpoint, resolve_device(device))


def parse_request(data: bytes | str, metadata: Mapping[str, Any]) -> dict[str, Any]:
    """A request decoded and checked against the metadata's schema, or a RequestError."""
    if isinstance(data, str):
        raise RequestError("send msgpack binary frames (openpi_client.msgpack_numpy), "
                           "not text")
    try:
        request = msgpack_numpy.unpackb(data)
    except Exception as err:  # msgpack raises several unrelated types
        raise RequestError(f"the frame is not msgpack-numpy ({err})") from None
    if not isinstance(request, dict):
        raise RequestError(f"a request is a map of observation groups, got "
                           f"{type(request).__name__}")
    if request.get(RESET):
        seed = request.get(SEED)
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer)):
            raise RequestError(f"reset's seed must be an integer, got {seed!r}")
        return request
    shapes = metadata["shapes"]
    missing = [g for g in shapes if g not in request]
    if missing:
        raise RequestError(f"the request lacks observation groups {missing}; this policy "
                           f"reads {list(shapes)} (shapes {json.dumps(shapes)}), or send "
                           f"{{\"{RESET}\": true}}")
    for group, shape in shapes.items():
        value = request[group]
        if not isinstance(value, np.ndarray | np.generic | list | int | float):
            raise RequestError(f"group {group!r} must be an array, got {type(value).__name__}")
        array = np.asarray(value)
        if array.dtype.kind not in "biuf":
            raise RequestError(f"group {group!r} has dtype {array.dtype}; send real numbers "
                               f"({metadata['dtypes'][group]})")
        if list(array.shape) != list(shape):
            raise RequestError(f"group {group!r} has shape {list(array.shape)}; one frame "
                               f"of it is {list(shape)} (no batch or time axis)")
        if not np.isfinite(array).all():
            raise RequestError(f"group {group!r} holds non-finite values")
        request[group] = array
    return request


class PolicyServer:
    """The websocket server: one thread and one `Session` per connection."""

    def __init__(self, served: Served, host: str = "0.0.0.0",
                 port: int = 8000, seed: int = 0) -> None:
        self.served, self.seed = served, seed
        self._metadata = msgpack_numpy.packb(served.metadata)
        self._server: Server = serve(self._handle, host, port, compression=None,
                                     max_size=None)
        self.port = int(self._server.socket.getsockname()[1])

    def serve_forever(self) -> None:
        self._server.serve_forever()

    def shutdown(self) -> None:
        self._server.shutdown()

    def _handle(self, ws: ServerConnection) -> None:
        session = self.served.session(self.seed)
        ws.send(self._metadata)
        while True:
            try:
                data = ws.recv()
            except ConnectionClosed:
                return
            try:
                ws.send(msgpack_numpy.packb(self._answer(session, data)))
            except RequestError as err:
                ws.send(f"error: {err}")
            except ConnectionClosed:
                return
            except Exception:
                log.exception("request from %s failed", ws.remote_address)
                ws.send(traceback.format_exc())
                ws.close(code=CloseCode.INTERNAL_ERROR,
                         reason="Internal server error. Traceback included in previous frame.")
                return

    def _answer(self, session: Session, data: bytes | str) -> dict[str, Any]:
        request = parse_request(data, self.served.metadata)
        if request.get(RESET):
            seed = request.get(SEED)
            session.reset(self.seed if seed is None else int(seed))
            return {RESET: True}
        observe_only = bool(request.get(OBSERVE_ONLY, False))
        chunk = session.step({g: request[g] for g in self.served.metadata["groups"]},
                             not observe_only)
        return {"observed": True} if chunk is None else {ACTIONS: chunk.astype(np.float32)}

