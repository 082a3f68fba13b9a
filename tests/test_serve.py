"""`python -m dexbench serve`: a tiny DP checkpoint behind openpi's websocket protocol,
queried by openpi-client's own `WebsocketClientPolicy` (two concurrent clients, reset,
malformed requests) and by `eval.py policy=openpi` as a round trip."""

import json
import pathlib
import subprocess
import sys
import threading

import numpy as np
import pytest
from openpi_client import msgpack_numpy as openpi_msgpack
from openpi_client.websocket_client_policy import WebsocketClientPolicy
from websockets.sync.client import connect

from dexbench.cli import collect as collect_cli
from dexbench.cli import eval as eval_cli
from dexbench.cli import train as train_cli
from dexbench.cli.config import ConfigError
from dexbench.cli.serve import serve as serve_cli
from dexbench.policies.serving import PolicyServer, load_served

REPO = pathlib.Path(__file__).resolve().parents[1]
TINY_DP = ["policy.unet.channels=[8,16]", "policy.unet.step_embed_dim=8",
           "policy.encoder.hidden=16", "policy.encoder.out=8", "policy.optim.batch_size=16",
           "policy.noise.num_inference_steps=3"]
# openpi-client 0.1.2 opens its connection the way websockets >= 15 deprecates
pytestmark = pytest.mark.filterwarnings("ignore:connect\\(\\) must be used:DeprecationWarning")


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory) -> pathlib.Path:
    """A tiny PickCube DP trained for 2 steps on 2 expert demonstrations."""
    root = tmp_path_factory.mktemp("runs")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("DEXBENCH_RUNS_DIR", str(root))
        data = root / "datasets" / "PickCube"
        assert collect_cli.main(["task=PickCube", "num_demos=2", "num_envs=2",
                                 "post_success_steps=2", f"out={data}", "progress=false",
                                 "sim.nthread=1"]) == 0
        assert train_cli.main(["policy=dp", "task=PickCube", f"dataset={data}",
                               "train.max_steps=2", "device=cpu", "progress=false",
                               *TINY_DP]) == 0
    (last,) = (root / "train").rglob("last.pt")
    return last.parent


@pytest.fixture(scope="module")
def server(checkpoint):
    srv = PolicyServer(load_served("dp", str(checkpoint), "cpu"), "127.0.0.1", 0)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    yield srv
    srv.shutdown()


def _frame(meta: dict, value: float) -> dict:
    return {g: np.full(meta["shapes"][g], value, np.float32) for g in meta["groups"]}


def test_metadata_schema(server):
    meta = WebsocketClientPolicy("127.0.0.1", server.port).get_server_metadata()
    assert meta["server"] == "dexbench" and meta["kind"] == "dp"
    assert meta["task"] == "PickCube" and meta["embodiment"] == "floating_shadow"
    assert meta["groups"] and set(meta["shapes"]) == set(meta["dtypes"]) == set(meta["groups"])
    assert meta["n_obs_steps"] == 2 and meta["chunk_length"] == 8
    assert meta["action_dim"] == len(meta["action_layout"]) > 0
    assert meta["actions_key"] == "actions"


def test_concurrent_clients_keep_their_own_history_and_reset(server):
    meta = WebsocketClientPolicy("127.0.0.1", server.port).get_server_metadata()
    a, b = _frame(meta, 0.1), _frame(meta, 0.9)
    sequences = [[a, b, a], [b, a, a]]

    def run(frames: list[dict]) -> list[np.ndarray]:
        client = WebsocketClientPolicy("127.0.0.1", server.port)
        return [client.infer({**f, "prompt": "ignored"})["actions"] for f in frames]

    alone = [run(seq) for seq in sequences]
    together: list = [None, None]

    def worker(k: int) -> None:
        together[k] = run(sequences[k])

    threads = [threading.Thread(target=worker, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k in range(2):  # side by side, each client gets what it gets alone
        for got, want in zip(together[k], alone[k], strict=True):
            assert got.shape == (8, meta["action_dim"]) and got.dtype == np.float32
            np.testing.assert_array_equal(got, want)
    # the history matters: the same last frame after other frames plans otherwise
    assert not np.array_equal(alone[0][2], alone[1][2])

    client = WebsocketClientPolicy("127.0.0.1", server.port)
    first = client.infer(a)["actions"]
    assert client.infer({**b, "observe_only": True}) == {"observed": True}
    assert client.infer({"reset": True}) == {"reset": True}
    np.testing.assert_array_equal(client.infer(a)["actions"], first)  # as if new


def test_malformed_requests_get_an_error_and_the_server_serves_on(server):
    client = WebsocketClientPolicy("127.0.0.1", server.port)
    meta = client.get_server_metadata()
    good = _frame(meta, 0.5)
    group = meta["groups"][0]
    bad = [({"prompt": "pick"}, "lacks observation groups"),
           ({**good, group: np.zeros(3, np.float32)}, "has shape"),
           ({**good, group: "text"}, "must be an array"),
           ({**good, group: np.full(meta["shapes"][group], np.nan)}, "non-finite"),
           ({"reset": True, "seed": "x"}, "seed must be an integer")]
    for request, message in bad:
        with pytest.raises(RuntimeError, match=f"Error in inference server:\nerror: .*{message}"):
            client.infer(request)
    assert client.infer(good)["actions"].shape == (8, meta["action_dim"])
    with connect(f"ws://127.0.0.1:{server.port}") as raw:
        raw.recv()  # metadata
        for frame in (b"\xc1not msgpack", "a text frame", openpi_msgpack.packb([1, 2])):
            raw.send(frame)
            assert raw.recv().startswith("error: ")
        raw.send(openpi_msgpack.packb(good))
        assert "actions" in openpi_msgpack.unpackb(raw.recv())


def test_eval_policy_openpi_round_trip(server, capsys, monkeypatch):
    frames: list[bool] = []  # whether each frame the server took was planned for
    make_session = server.served.session

    def counting(seed: int):
        session = make_session(seed)
        step = session.step
        session.step = lambda frame, plan: frames.append(plan) or step(frame, plan)
        return session

    monkeypatch.setattr(server.served, "session", counting)
    code = eval_cli.main(["task=PickCube", "policy=openpi", "policy.host=127.0.0.1",
                          f"policy.port={server.port}", "policy.replan_steps=8", "episodes=2",
                          "num_envs=2", "horizon=20", "sim.nthread=1", "progress=false"])
    assert code == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["episodes"] == 2 and result["complete"]
    # 2 envs x 20 steps: every step's frame reaches the server, a plan every 8 steps
    assert len(frames) == 40 and sum(frames) == 2 * 3


def test_serve_command(checkpoint):
    with pytest.raises(ConfigError, match="scripted from the simulator"):
        serve_cli(["policy=expert"])
    with pytest.raises(ConfigError, match="needs checkpoint="):
        serve_cli(["policy=dp"])
    proc = subprocess.Popen([sys.executable, "-m", "dexbench", "serve", "policy=dp",
                             f"checkpoint={checkpoint}", "host=127.0.0.1", "port=0",
                             "device=cpu"], cwd=REPO, stdout=subprocess.PIPE, text=True)
    try:
        port = json.loads(proc.stdout.readline())["port"]
        client = WebsocketClientPolicy("127.0.0.1", port)
        meta = client.get_server_metadata()
        assert client.infer(_frame(meta, 0.5))["actions"].shape == (8, meta["action_dim"])
    finally:
        proc.terminate()
        proc.wait(timeout=30)
