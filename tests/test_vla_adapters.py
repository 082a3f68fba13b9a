"""VLA adapters against the peers' own code.

The wire formats are checked in both directions against the packages the model servers
use: openpi's `openpi_client.msgpack_numpy` and the `json_numpy` package OpenVLA-OFT's
deploy server patches into its JSON. `policy=openpi` runs against a small websocket
server that behaves as openpi's `WebsocketPolicyServer` (openpi-client ships none): the
metadata frame first, openpi-client's codec, an error as a text frame then close 1011;
openpi-client's own `WebsocketClientPolicy` checks that server. `policy=openvla_oft` runs
against a REST server that decodes and encodes with `json_numpy` as the deploy server
does. Also: image resizing, chunk playback and re-planning, the evaluator end to end and
each failure's message.
"""

import http.server
import json
import math
import pathlib
import threading
import traceback

import json_numpy
import numpy as np
import pytest
import torch
import yaml
from openpi_client import msgpack_numpy as openpi_msgpack
from openpi_client.websocket_client_policy import WebsocketClientPolicy
from websockets.exceptions import ConnectionClosed
from websockets.frames import CloseCode
from websockets.sync.client import connect
from websockets.sync.server import serve

from dexbench import make_env
from dexbench.cli import eval as eval_cli
from dexbench.cli.eval import EvalError
from dexbench.eval.throughput import WARMUP_STEPS
from dexbench.policies.vla_adapters import json_numpy as our_json
from dexbench.policies.vla_adapters import msgpack_numpy as our_msgpack
from dexbench.policies.vla_adapters import openpi, openvla_oft
from dexbench.policies.vla_adapters.chunks import RemotePolicyError
from dexbench.policies.vla_adapters.images import resize_with_pad

REPO = pathlib.Path(__file__).resolve().parents[1]


def _yaml_options(kind: str) -> dict:
    return {k: v for k, v in yaml.safe_load(
        (REPO / f"conf/policy/{kind}.yaml").read_text()).items() if k != "name"}


OPTIONS = _yaml_options("openpi")
OFT_OPTIONS = _yaml_options("openvla_oft")
SIZE = 32  # camera and request image size in these tests
ARRAYS = [
    np.arange(6, dtype=np.float32).reshape(2, 3), np.zeros((0, 4), np.int64),
    np.array([True, False]), np.random.default_rng(0).integers(0, 256, (SIZE, SIZE, 3),
                                                               dtype=np.uint8),
    np.asfortranarray(np.arange(12, dtype=np.int16).reshape(3, 4)),
    np.random.default_rng(1).normal(size=30),  # float64, not float32-representable
]
SCALARS = [np.uint8(7), np.float32(1.5), np.int64(-3)]  # np.float64 is a float: sent as one


def _same(got, want) -> None:
    """`got` is an array (or NumPy scalar) equal to `want` in type, dtype, shape, values."""
    assert isinstance(got, np.ndarray if isinstance(want, np.ndarray) else np.generic)
    assert got.dtype == want.dtype and np.shape(got) == np.shape(want)
    np.testing.assert_array_equal(got, want)


# msgpack: openpi's codec on the other end


@pytest.mark.parametrize("value", ARRAYS + SCALARS)
def test_openpi_client_decodes_what_we_send(value):
    _same(openpi_msgpack.unpackb(our_msgpack.packb({"x": value}))["x"], value)


@pytest.mark.parametrize("value", ARRAYS + SCALARS)
def test_we_decode_what_openpi_client_sends(value):
    back = our_msgpack.unpackb(openpi_msgpack.packb({"x": value}))["x"]
    _same(back, value)
    if isinstance(back, np.ndarray):
        back[...] = 0  # decoded arrays are writable copies


def test_msgpack_nested_requests_and_refused_dtypes():
    request = {"observation/image": ARRAYS[3], "prompt": "pick", "n": [np.float32(1.5), 3]}
    back = openpi_msgpack.unpackb(our_msgpack.packb(request))
    _same(back["observation/image"], ARRAYS[3])
    assert back["prompt"] == "pick" and back["n"] == [1.5, 3]
    _same(back["n"][0], np.float32(1.5))
    # a plain dict that merely has the marker as a *string* key stays a dict, as in openpi
    plain = {"__ndarray__": True, "data": b"", "dtype": "<f4", "shape": [0]}
    assert our_msgpack.unpackb(openpi_msgpack.packb(plain)) == plain
    with pytest.raises(TypeError, match="dtype object"):
        our_msgpack.packb(np.array([None, 1], dtype=object))


# json: the json-numpy package on the other end


@pytest.mark.parametrize("value", ARRAYS + SCALARS)
def test_json_numpy_decodes_what_we_send(value):
    back = json_numpy.loads(our_json.dumps({"x": value, "n": 3}))
    assert back["n"] == 3
    _same(back["x"], value)


@pytest.mark.parametrize("value", ARRAYS + SCALARS)
def test_we_decode_what_json_numpy_sends(value):
    back = our_json.loads(json_numpy.dumps({"x": value, "n": 3}))
    assert back["n"] == 3
    _same(back["x"], value)


def test_resize_with_pad_keeps_aspect_and_letterboxes():
    frames = torch.full((2, 48, 64, 3), 200, dtype=torch.uint8)
    out = resize_with_pad(frames, 32)
    assert out.shape == (2, 32, 32, 3) and out.dtype == torch.uint8
    assert (out[:, :4] == 0).all() and (out[:, 28:] == 0).all()  # 24 rows of picture
    assert (out[:, 4:28] == 200).all()
    square = resize_with_pad(torch.full((1, 64, 64, 3), 9, dtype=torch.uint8), 16)
    assert (square == 9).all()


# openpi: a WebsocketPolicyServer stand-in


def _parse_images(obs: dict) -> None:
    """What openpi's LIBERO input transform does first with each image: `np.asarray`,
    then look at its shape (a dict where an array should be fails here)."""
    for key, value in obs.items():
        if "image" in key:
            image = np.asarray(value)
            assert image.shape[-1] == 3 and image.dtype == np.uint8, key


def _zeros_policy(rows: int, dim: int = 26):
    def policy(obs: dict) -> dict:
        _parse_images(obs)
        return {"actions": np.zeros((rows, dim), np.float32)}
    return policy


class OpenpiTestServer:
    """openpi's `WebsocketPolicyServer` in miniature, speaking through openpi-client's
    `msgpack_numpy`: on connect the metadata; per binary frame unpack, `policy(obs)`, pack
    the result with the `server_timing` openpi adds; on an exception the traceback as a
    text frame, then close with 1011 (internal error). Records every request."""

    def __init__(self) -> None:
        self.requests: list[dict] = []
        self.metadata = {"server": "test"}
        self.policy = _zeros_policy(4)
        self._server = serve(self._handler, "127.0.0.1", 0, compression=None, max_size=None)
        self.port = self._server.socket.getsockname()[1]
        threading.Thread(target=self._server.serve_forever, daemon=True).start()

    def _handler(self, websocket) -> None:
        packer = openpi_msgpack.Packer()
        websocket.send(packer.pack(self.metadata))
        while True:
            try:
                obs = openpi_msgpack.unpackb(websocket.recv())
                self.requests.append(obs)
                action = dict(self.policy(obs))
                action["server_timing"] = {"infer_ms": 0.1}
                websocket.send(packer.pack(action))
            except ConnectionClosed:
                return
            except Exception:
                websocket.send(traceback.format_exc())
                websocket.close(code=CloseCode.INTERNAL_ERROR,
                                reason="Internal server error. Traceback included in previous "
                                       "frame.")
                return

    def close(self) -> None:
        self._server.shutdown()


@pytest.fixture
def server():
    srv = OpenpiTestServer()
    yield srv
    srv.close()


def _failing_policy(obs: dict) -> dict:
    raise ValueError("model exploded")


# openpi-client 0.1.2 opens its connection the way websockets >= 15 deprecates
@pytest.mark.filterwarnings("ignore:connect\\(\\) must be used:DeprecationWarning")
def test_the_test_server_speaks_openpi_to_openpi_clients(server):
    client = WebsocketClientPolicy("127.0.0.1", server.port)
    assert client.get_server_metadata() == {"server": "test"}
    reply = client.infer({"observation/image": ARRAYS[3], "prompt": "pick"})
    _same(reply["actions"], np.zeros((4, 26), np.float32))
    _same(server.requests[0]["observation/image"], ARRAYS[3])
    server.policy = _failing_policy
    with pytest.raises(RuntimeError, match=r"(?s)Error in inference server.*model exploded"):
        client.infer({"prompt": "pick"})
    with connect(f"ws://127.0.0.1:{server.port}") as raw:
        raw.recv()  # metadata
        raw.send(openpi_msgpack.packb({"prompt": "pick"}))
        assert "ValueError: model exploded" in raw.recv()  # a text frame
        with pytest.raises(ConnectionClosed) as closed:
            raw.recv()
        assert closed.value.rcvd.code == CloseCode.INTERNAL_ERROR


def _options(server, base: dict = OPTIONS, **overrides) -> dict:
    """`base` settings pointed at a test `server`, with small images."""
    return {**base, "host": "127.0.0.1", "port": server.port, "image_size": SIZE,
            "timeout_s": 10, **overrides}


def _env(num_envs: int = 2):
    spec = openpi.spec(None, OPTIONS)
    return make_env("PickCube", num_envs=num_envs, obs=list(spec.obs),
                    cameras=list(spec.cameras), image_size=(SIZE, SIZE))


def test_openpi_requests_and_chunk_playback(server):
    env = _env(2)
    chunk = env.home_action.numpy()[None] + 0.01 * np.arange(4, dtype=np.float32)[:, None]
    server.policy = lambda obs: {"actions": chunk}
    policy = openpi.build(None, env, "cpu", _options(server, replan_steps=3))
    obs = first = env.reset()
    played = []
    for _ in range(7):
        action = policy.act(obs)
        played.append(action.numpy())
        obs, *_ = env.step(action)
    # each env asks at steps 0, 3 and 6 and plays the chunk's first 3 rows
    assert len(server.requests) == 6 and policy.queries == 6
    for step, rows in enumerate(played):
        np.testing.assert_allclose(rows, np.stack([chunk[step % 3]] * 2), atol=1e-6)
    request = server.requests[0]  # as openpi-client decoded it
    assert set(request) == {"observation/image", "observation/wrist_image",
                            "observation/state", "prompt"}
    assert request["prompt"] == env.task.instruction
    for key in ("observation/image", "observation/wrist_image"):
        assert isinstance(request[key], np.ndarray)
        assert request[key].shape == (SIZE, SIZE, 3) and request[key].dtype == np.uint8
    _same(request["observation/state"], first["proprio"][0].numpy())
    _same(server.requests[1]["observation/state"], first["proprio"][1].numpy())
    assert request["observation/state"].shape == (30,)
    # the front view and the wrist view differ (both cameras are really sent)
    assert not np.array_equal(request["observation/image"], request["observation/wrist_image"])
    # a reset env drops its queue and asks again at once; the other plays on
    policy.act(obs)  # step 7: both envs play their 2nd row
    policy.reset(torch.tensor([1]))
    before = len(server.requests)
    policy.act(obs)
    assert len(server.requests) == before + 1


def test_openpi_sends_what_the_settings_name(server):
    env = _env(1)
    server.policy = lambda obs: {"act": np.zeros((2, 26))}
    options = _options(server, state_key=None, prompt_key="task", prompt="lift it",
                       cameras=["front"], image_keys=["image"], actions_key="act")
    policy = openpi.build(None, env, "cpu", options)
    policy.act(env.reset())
    assert set(server.requests[0]) == {"image", "task"}
    assert server.requests[0]["task"] == "lift it"
    assert isinstance(server.requests[0]["image"], np.ndarray)


def test_openpi_eval_cli_end_to_end(server, capsys):
    server.policy = _zeros_policy(10)
    code = eval_cli.main(["task=PickCube", "policy=openpi", "policy.host=127.0.0.1",
                          f"policy.port={server.port}", f"policy.image_size={SIZE}",
                          "episodes=3", "num_envs=1", "horizon=12", f"camera.width={SIZE}",
                          f"camera.height={SIZE}", "progress=false"])
    assert code == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["episodes"] == 3 and result["complete"]
    # 3 episodes of 12 steps, 10 actions per query: 2 queries per episode
    assert len(server.requests) == 6
    for request in server.requests:
        assert request["observation/image"].shape == (SIZE, SIZE, 3)
        assert request["observation/state"].dtype == np.float32
    server.policy = _failing_policy  # the server's traceback ends the run
    with pytest.raises(RemotePolicyError, match="ValueError: model exploded"):
        eval_cli.main(["task=PickCube", "policy=openpi", "policy.host=127.0.0.1",
                       f"policy.port={server.port}", f"policy.image_size={SIZE}",
                       "episodes=1", "num_envs=1", "horizon=2", f"camera.width={SIZE}",
                       f"camera.height={SIZE}", "progress=false"])


def test_openpi_eval_resumes_with_another_server_but_not_other_settings(server):
    server.policy = _zeros_policy(10)
    args = ["task=PickCube", "policy=openpi", "policy.host=127.0.0.1",
            f"policy.image_size={SIZE}", "episodes=2", "num_envs=2", "horizon=3",
            f"camera.width={SIZE}", f"camera.height={SIZE}", "progress=false", "name=vla"]
    assert eval_cli.main([*args, f"policy.port={server.port}"]) == 0
    asked = len(server.requests)
    moved = OpenpiTestServer()  # the same model restarted elsewhere: the run resumes
    try:
        assert eval_cli.main([*args, f"policy.port={moved.port}"]) == 0
        assert len(server.requests) == asked and not moved.requests  # nothing left to run
    finally:
        moved.close()
    with pytest.raises(EvalError, match="policy_settings"):
        eval_cli.main([*args, f"policy.port={server.port}", "policy.replan_steps=5"])


def test_openpi_eval_throughput_benchmark_needs_no_checkpoint(server):
    server.policy = _zeros_policy(10)
    result = eval_cli.bench_eval([
        "policy=openpi", "policy.host=127.0.0.1", f"policy.port={server.port}",
        f"policy.image_size={SIZE}", "num_envs=2", "episodes=2", "sequential_episodes=1",
        "horizon=5", f"camera.width={SIZE}", f"camera.height={SIZE}", "progress=false"])
    assert result["policy"] == "openpi" and result["checkpoint"] is None
    # untimed warm-up steps re-query every 10 (replan_steps), then one query per 5-step
    # episode: batched 2 envs x (warm-up + 1), sequential 1 env x (warm-up + 1)
    warmup = math.ceil(WARMUP_STEPS / 10)
    assert result["batched_eps_per_min"] > 0
    assert len(server.requests) == 2 * (warmup + 1) + (warmup + 1)


@pytest.mark.parametrize("model, message", [
    (_failing_policy, r"(?s)failed:.*Traceback.*ValueError: model exploded"),
    (_zeros_policy(4, 7), r"shape \(4, 7\)"),
    (lambda obs: {"actions": np.full((4, 26), np.nan)}, "non-finite"),
    (lambda obs: {"chunk": np.zeros((4, 26))}, r"no 'actions' \(got \['chunk', 'server_timing"),
])
def test_openpi_bad_answers_are_clear_errors(server, model, message):
    env = _env(1)
    server.policy = model
    policy = openpi.build(None, env, "cpu", _options(server))
    with pytest.raises(RemotePolicyError, match=message):
        policy.act(env.reset())


def test_openpi_unreachable_server_and_bad_settings():
    env = _env(1)
    closed = OpenpiTestServer()
    closed.close()
    with pytest.raises(RemotePolicyError, match="no openpi policy server answered"):
        openpi.build(None, env, "cpu", {**OPTIONS, "host": "127.0.0.1", "port": closed.port,
                                        "timeout_s": 5})
    with pytest.raises(ValueError, match="takes no checkpoint"):
        openpi.spec("model.pt", OPTIONS)
    with pytest.raises(ValueError, match="same number of images"):
        openpi.spec(None, {**OPTIONS, "image_keys": ["observation/image"]})
    with pytest.raises(ValueError, match="unknown \\['colour'\\]"):
        openpi.spec(None, {**OPTIONS, "colour": 1})


# OpenVLA-OFT: a REST server decoding and encoding with json_numpy


class OftTestServer:
    """POST /act as OpenVLA-OFT's `vla-scripts/deploy.py` serves it: the body parsed by
    json_numpy (the server patches it into `json`), the answer (`reply(request)`, the
    action chunk) encoded by json_numpy; a failed request answers the JSON string
    "error". A `str` answer is sent as that JSON string. Records every request."""

    def __init__(self) -> None:
        self.requests: list[dict] = []
        self.reply = lambda request: [np.zeros(26, np.float32)] * 8
        outer = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_POST(self) -> None:
                if self.path != "/act":
                    self.send_error(404)
                    return
                request = json_numpy.loads(self.rfile.read(int(self.headers["Content-Length"])))
                outer.requests.append(request)
                body = json_numpy.dumps(outer.reply(request)).encode()
                self.send_response(200)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args) -> None:
                """Quiet."""

        self._server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.port = self._server.server_address[1]
        threading.Thread(target=self._server.serve_forever, daemon=True).start()

    def close(self) -> None:
        self._server.shutdown()
        self._server.server_close()


@pytest.fixture
def oft_server():
    srv = OftTestServer()
    yield srv
    srv.close()


def test_openvla_oft_requests_and_chunk_playback(oft_server):
    env = _env(2)
    chunk = env.home_action.numpy()[None] + 0.01 * np.arange(8, dtype=np.float32)[:, None]
    oft_server.reply = lambda request: list(chunk)
    policy = openvla_oft.build(None, env, "cpu", _options(oft_server, OFT_OPTIONS))
    obs = first = env.reset()
    for step in range(9):
        action = policy.act(obs)
        np.testing.assert_allclose(action.numpy(), np.stack([chunk[step % 8]] * 2), atol=1e-6)
        obs, *_ = env.step(action)
    assert len(oft_server.requests) == 4  # each env at steps 0 and 8
    request = oft_server.requests[0]  # as json_numpy decoded it
    assert set(request) == {"full_image", "wrist_image", "state", "instruction"}
    assert request["instruction"] == env.task.instruction
    for key in ("full_image", "wrist_image"):
        assert isinstance(request[key], np.ndarray)
        assert request[key].shape == (SIZE, SIZE, 3) and request[key].dtype == np.uint8
    _same(request["state"], first["proprio"][0].numpy())


def test_openvla_oft_double_encoded_answer_and_failures(oft_server):
    env = _env(1)
    # the deploy server's answer to an `encoded` request: json_numpy text inside JSON
    oft_server.reply = lambda request: json_numpy.dumps(np.ones((8, 26), np.float32))
    policy = openvla_oft.build(None, env, "cpu", _options(oft_server, OFT_OPTIONS))
    assert (policy.act(env.reset()).numpy() == 1).all()
    oft_server.reply = lambda request: "error"
    policy = openvla_oft.build(None, env, "cpu", _options(oft_server, OFT_OPTIONS))
    with pytest.raises(RemotePolicyError, match="failed on the request"):
        policy.act(env.reset())
    wrong_route = _options(oft_server, OFT_OPTIONS, route="/predict")
    policy = openvla_oft.build(None, env, "cpu", wrong_route)
    with pytest.raises(RemotePolicyError, match="HTTP 404"):
        policy.act(env.reset())
    closed = OftTestServer()
    closed.close()
    policy = openvla_oft.build(None, env, "cpu", _options(closed, OFT_OPTIONS))
    with pytest.raises(RemotePolicyError, match="no OpenVLA-OFT server answered"):
        policy.act(env.reset())
    with pytest.raises(ValueError, match="takes no checkpoint"):
        openvla_oft.spec("model.pt", OFT_OPTIONS)
