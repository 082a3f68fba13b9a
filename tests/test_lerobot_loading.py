"""Loading a dataset `collect.py` wrote through LeRobot's own `LeRobotDataset`, with
`load_lerobot_dataset`: quietly (dexbench stores no video, so no FFmpeg/torchcodec
warning) and with the float64 simulator state bit for bit."""

import importlib
import logging

import numpy as np
import pyarrow.parquet as pq
import pytest
import torch
from lerobot.datasets import LeRobotDataset

from dexbench.cli import collect as collect_cli
from dexbench.data.features import SIM_STATE
from dexbench.data.lerobot_io import DATA_GLOB, load_lerobot_dataset


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    out = tmp_path_factory.mktemp("lerobot") / "PickCube"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("DEXBENCH_RUNS_DIR", str(out.parent / "runs"))
        assert collect_cli.main(["task=PickCube", "num_demos=2", "num_envs=2", f"out={out}",
                                 "progress=false"]) == 0
    return out


def _torchcodec_loads() -> bool:
    try:
        importlib.import_module("torchcodec")
    except (ImportError, OSError, RuntimeError):  # what LeRobot catches, then warns about
        return False
    return True


def _said(capfd, caplog) -> str:
    """Everything written to stdout/stderr or logged at WARNING or above, then cleared."""
    out, err = capfd.readouterr()
    logged = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    caplog.clear()
    return "\n".join([out, err, *logged])


def test_loading_is_quiet(root, capfd, caplog):
    caplog.set_level(logging.INFO)
    _said(capfd, caplog)
    dataset = load_lerobot_dataset(root)
    dataset[0]
    assert _said(capfd, caplog).strip() == ""
    # the capture sees LeRobot's warning where a plain load gives it (FFmpeg missing)
    LeRobotDataset(f"dexbench/{root.name}", root=root)
    assert ("torchcodec" in _said(capfd, caplog)) != _torchcodec_loads()


def test_sim_state_comes_back_bit_exact(root):
    stored = np.concatenate([
        np.stack(pq.read_table(f, columns=[SIM_STATE]).column(SIM_STATE).to_numpy(
            zero_copy_only=False)) for f in sorted(root.glob(DATA_GLOB))])
    assert stored.dtype == np.float64
    assert not np.array_equal(stored.astype(np.float32), stored)  # float32 would lose bits
    dataset = load_lerobot_dataset(root)
    assert len(dataset) == len(stored)
    for index in (0, 1, len(stored) - 1):
        frame = dataset[index]
        assert frame[SIM_STATE].dtype == torch.float64
        np.testing.assert_array_equal(frame[SIM_STATE].numpy(), stored[index])
        assert frame["action"].dtype == torch.float32  # other features as LeRobot gives them
    fps = dataset.fps
    window = load_lerobot_dataset(root, delta_timestamps={SIM_STATE: [-1 / fps, 0.0]})
    np.testing.assert_array_equal(window[1][SIM_STATE].numpy(), stored[0:2])
    loader = torch.utils.data.DataLoader(dataset, batch_size=4)
    np.testing.assert_array_equal(next(iter(loader))[SIM_STATE].numpy(), stored[:4])
