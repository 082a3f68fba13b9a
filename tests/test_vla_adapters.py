"""VLA adapters: the msgpack-numpy and json-numpy wire formats, image resizing,
`policy=openpi` against an in-process server speaking openpi's websocket protocol
(requests, chunk playback, re-planning after resets, the evaluator end to end, each
failure's message) and `policy=openvla_oft` against an in-process REST server."""

import http.server
import json
import pathlib
import threading

import msgpack
import numpy as np
import pytest
import torch
import yaml
from websockets.sync.server import serve

from dexbench import make_env
from dexbench.cli import eval as eval_cli
from dexbench.cli.eval import EvalError
from dexbench.policies.vla_adapters import json_numpy, msgpack_numpy, openpi, openvla_oft
from dexbench.policies.vla_adapters.chunks import RemotePolicyError
from dexbench.policies.vla_adapters.images import resize_with_pad

REPO = pathlib.Path(__file__).resolve().parents[1]


def _yaml_options(kind: str) -> dict:
    return {k: v for k, v in yaml.safe_load(
        (REPO / f"conf/policy/{kind}.yaml").read_text()).items() if k != "name"}


OPTIONS = _yaml_options("openpi")
OFT_OPTIONS = _yaml_options("openvla_oft")
SIZE = 32  # camera and request image size in these tests


class FakeOpenpiServer:
    """Sends metadata on connect, records each request and answers with `reply(request)`."""

    def __init__(self) -> None:
        self.requests: list[dict] = []
        self.reply = lambda request: {"actions": np.zeros((4, 26), np.float32)}
        self._server = serve(self._handle, "127.0.0.1", 0, compression=None, max_size=None)
        self.port = self._server.socket.getsockname()[1]
        threading.Thread(target=self._server.serve_forever, daemon=True).start()

    def _handle(self, conn) -> None:
        conn.send(msgpack_numpy.packb({"server": "fake"}))
        for message in conn:
            request = msgpack_numpy.unpackb(message)
            self.requests.append(request)
            answer = self.reply(request)
            conn.send(answer if isinstance(answer, str) else msgpack_numpy.packb(answer))

    def close(self) -> None:
        self._server.shutdown()


@pytest.fixture
def server():
    srv = FakeOpenpiServer()
    yield srv
    srv.close()


def _options(server, base: dict = OPTIONS, **overrides) -> dict:
    """`base` settings pointed at a test `server`, with small images."""
    return {**base, "host": "127.0.0.1", "port": server.port, "image_size": SIZE,
            "timeout_s": 10, **overrides}


def _env(num_envs: int = 2):
    spec = openpi.spec(None, OPTIONS)
    return make_env("PickCube", num_envs=num_envs, obs=list(spec.obs),
                    cameras=list(spec.cameras), image_size=(SIZE, SIZE))


@pytest.mark.parametrize("value", [
    np.arange(6, dtype=np.float32).reshape(2, 3), np.zeros((0, 4), np.int64),
    np.array([True, False]), np.uint8(7), {"a": [np.float32(1.5), "x", 3]},
    np.asfortranarray(np.arange(12, dtype=np.int16).reshape(3, 4)),
])
def test_msgpack_numpy_round_trips(value):
    back = msgpack_numpy.unpackb(msgpack_numpy.packb(value))
    if isinstance(value, dict):
        assert back == value
        assert isinstance(back["a"][0], np.float32)
    else:
        np.testing.assert_array_equal(back, value)
        assert back.dtype == value.dtype and np.shape(back) == np.shape(value)


def test_msgpack_numpy_reads_openpi_byte_keys_and_refuses_objects():
    raw = msgpack.packb({"actions": {b"__ndarray__": True, b"data": np.ones(6, "<f4").tobytes(),
                                     b"dtype": "<f4", b"shape": (3, 2)}})
    actions = msgpack_numpy.unpackb(raw)["actions"]
    assert actions.shape == (3, 2) and actions.dtype == np.float32 and (actions == 1).all()
    actions[0, 0] = 2.0  # decoded arrays are writable copies
    with pytest.raises(TypeError, match="dtype object"):
        msgpack_numpy.packb(np.array([None, 1], dtype=object))


def test_resize_with_pad_keeps_aspect_and_letterboxes():
    frames = torch.full((2, 48, 64, 3), 200, dtype=torch.uint8)
    out = resize_with_pad(frames, 32)
    assert out.shape == (2, 32, 32, 3) and out.dtype == torch.uint8
    assert (out[:, :4] == 0).all() and (out[:, 28:] == 0).all()  # 24 rows of picture
    assert (out[:, 4:28] == 200).all()
    square = resize_with_pad(torch.full((1, 64, 64, 3), 9, dtype=torch.uint8), 16)
    assert (square == 9).all()


def test_openpi_requests_and_chunk_playback(server):
    env = _env(2)
    chunk = env.home_action.numpy()[None] + 0.01 * np.arange(4, dtype=np.float32)[:, None]
    server.reply = lambda request: {"actions": chunk}
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
    request = server.requests[0]
    assert set(request) == {"observation/image", "observation/wrist_image",
                            "observation/state", "prompt"}
    assert request["prompt"] == env.task.instruction
    for key in ("observation/image", "observation/wrist_image"):
        assert request[key].shape == (SIZE, SIZE, 3) and request[key].dtype == np.uint8
    np.testing.assert_array_equal(request["observation/state"], first["proprio"][0].numpy())
    np.testing.assert_array_equal(server.requests[1]["observation/state"],
                                  first["proprio"][1].numpy())
    assert request["observation/state"].shape == (30,)
    assert request["observation/state"].dtype == np.float32
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
    server.reply = lambda request: {"act": np.zeros((2, 26))}
    options = _options(server, state_key=None, prompt_key="task", prompt="lift it",
                       cameras=["front"], image_keys=["image"], actions_key="act")
    policy = openpi.build(None, env, "cpu", options)
    policy.act(env.reset())
    assert set(server.requests[0]) == {"image", "task"}
    assert server.requests[0]["task"] == "lift it"


def test_openpi_eval_cli_end_to_end(server, capsys):
    server.reply = lambda request: {"actions": np.zeros((10, 26), np.float32)}
    code = eval_cli.main(["task=PickCube", "policy=openpi", "policy.host=127.0.0.1",
                          f"policy.port={server.port}", f"policy.image_size={SIZE}",
                          "episodes=3", "num_envs=1", "horizon=12", f"camera.width={SIZE}",
                          f"camera.height={SIZE}", "progress=false"])
    assert code == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["episodes"] == 3 and result["complete"]
    # 3 episodes of 12 steps, 10 actions per query: 2 queries per episode
    assert len(server.requests) == 6


def test_openpi_eval_resumes_with_another_server_but_not_other_settings(server):
    server.reply = lambda request: {"actions": np.zeros((10, 26), np.float32)}
    args = ["task=PickCube", "policy=openpi", "policy.host=127.0.0.1",
            f"policy.image_size={SIZE}", "episodes=2", "num_envs=2", "horizon=3",
            f"camera.width={SIZE}", f"camera.height={SIZE}", "progress=false", "name=vla"]
    assert eval_cli.main([*args, f"policy.port={server.port}"]) == 0
    asked = len(server.requests)
    moved = FakeOpenpiServer()  # the same model restarted elsewhere: the run resumes
    try:
        assert eval_cli.main([*args, f"policy.port={moved.port}"]) == 0
        assert len(server.requests) == asked and not moved.requests  # nothing left to run
    finally:
        moved.close()
    with pytest.raises(EvalError, match="policy_settings"):
        eval_cli.main([*args, f"policy.port={server.port}", "policy.replan_steps=5"])


def test_openpi_eval_throughput_benchmark_needs_no_checkpoint(server):
    server.reply = lambda request: {"actions": np.zeros((10, 26), np.float32)}
    result = eval_cli.bench_eval([
        "policy=openpi", "policy.host=127.0.0.1", f"policy.port={server.port}",
        f"policy.image_size={SIZE}", "num_envs=2", "episodes=2", "sequential_episodes=1",
        "horizon=5", f"camera.width={SIZE}", f"camera.height={SIZE}", "progress=false"])
    assert result["policy"] == "openpi" and result["checkpoint"] is None
    # one untimed warm-up query per env, then one per 5-step episode: (2 + 2) + (1 + 1)
    assert result["batched_eps_per_min"] > 0 and len(server.requests) == 6


@pytest.mark.parametrize("reply, message", [
    (lambda r: "Traceback: model exploded", "model exploded"),
    (lambda r: {"actions": np.zeros((4, 7))}, r"shape \(4, 7\)"),
    (lambda r: {"actions": np.full((4, 26), np.nan)}, "non-finite"),
    (lambda r: {"chunk": np.zeros((4, 26))}, "no 'actions'"),
])
def test_openpi_bad_answers_are_clear_errors(server, reply, message):
    env = _env(1)
    server.reply = reply
    policy = openpi.build(None, env, "cpu", _options(server))
    with pytest.raises(RemotePolicyError, match=message):
        policy.act(env.reset())


def test_openpi_unreachable_server_and_bad_settings():
    env = _env(1)
    closed = FakeOpenpiServer()
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


@pytest.mark.parametrize("value", [
    np.arange(6, dtype=np.float32).reshape(2, 3), np.array([[1, 2]], dtype=np.uint8),
    np.asfortranarray(np.arange(12, dtype=np.int16).reshape(3, 4)), np.float32(2.5),
])
def test_json_numpy_round_trips_in_the_packages_layout(value):
    text = json_numpy.dumps({"x": value, "n": 3})
    layout = json.loads(text)["x"]
    assert set(layout) == {"__numpy__", "dtype", "shape"}
    assert layout["dtype"] == value.dtype.str and layout["shape"] == list(np.shape(value))
    back = json_numpy.loads(text)
    assert back["n"] == 3 and back["x"].dtype == value.dtype
    np.testing.assert_array_equal(back["x"], value)


class FakeOftServer:
    """A REST server answering POST /act like OpenVLA-OFT's deploy script."""

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
                answer = outer.reply(request)
                body = (json.dumps(answer) if isinstance(answer, str)
                        else json_numpy.dumps(answer)).encode()
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
    srv = FakeOftServer()
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
    request = oft_server.requests[0]
    assert set(request) == {"full_image", "wrist_image", "state", "instruction"}
    assert request["instruction"] == env.task.instruction
    assert request["full_image"].shape == (SIZE, SIZE, 3)
    assert request["full_image"].dtype == np.uint8
    np.testing.assert_array_equal(request["state"], first["proprio"][0].numpy())


def test_openvla_oft_double_encoded_answer_and_failures(oft_server):
    env = _env(1)
    oft_server.reply = lambda request: json_numpy.dumps([np.ones(26, np.float32)] * 8)
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
    closed = FakeOftServer()
    closed.close()
    policy = openvla_oft.build(None, env, "cpu", _options(closed, OFT_OPTIONS))
    with pytest.raises(RemotePolicyError, match="no OpenVLA-OFT server answered"):
        policy.act(env.reset())
    with pytest.raises(ValueError, match="takes no checkpoint"):
        openvla_oft.spec("model.pt", OFT_OPTIONS)
