"""Datasets on disk in the LeRobotDataset v3 layout, written by LeRobot's own writer.

Images (RGB and depth) are LeRobot `image` features: PNG/TIFF bytes inside the parquet
files, lossless and with no video codec needed. Reading back for replay and resume goes
straight to the parquet files (float64 simulator states stay float64); users load a
dataset through LeRobot with `load_lerobot_dataset`.
"""

from __future__ import annotations

import functools
import json
import pathlib
from typing import Any

import datasets
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import torch
from lerobot.datasets import LeRobotDataset
from lerobot.datasets.io_utils import hf_transform_to_torch

from dexbench.data.episode import Episode
from dexbench.data.features import ACTION, SIM_STATE
from dexbench.data.meta import DatasetError

DATA_GLOB = "data/chunk-*/file-*.parquet"


def create_dataset(root: pathlib.Path, features: dict, fps: int,
                   robot_type: str) -> LeRobotDataset:
    """An empty dataset at `root` (which must not exist yet), ready for `add_episode`."""
    datasets.disable_progress_bars()  # one bar per saved episode; ours tells progress
    return LeRobotDataset.create(repo_id=f"dexbench/{root.name}", fps=fps, features=features,
                                 root=root, robot_type=robot_type, use_videos=False,
                                 video_backend="pyav")


def load_lerobot_dataset(root: pathlib.Path | str, **kwargs: Any) -> LeRobotDataset:
    """A dexbench dataset as a `LeRobotDataset`, loaded quietly and with exact float64
    features (`sim_state`); `kwargs` go to `LeRobotDataset` (`delta_timestamps`, ...).

    Unless told a video backend, LeRobot tries to load torchcodec on every load and, where
    FFmpeg is missing, logs a ~50-line warning; dexbench stores no video, so PyAV is named
    and nothing is tried. LeRobot turns each numeric feature into a tensor of torch's
    default float32; here float64 features come back float64, bit for bit.
    """
    root = pathlib.Path(root)
    kwargs.setdefault("video_backend", "pyav")
    dataset = LeRobotDataset(f"dexbench/{root.name}", root=root, **kwargs)
    exact = [k for k, ft in dataset.meta.features.items() if ft["dtype"] == "float64"]
    # a partial, not a lambda: DataLoader workers started by spawn pickle the dataset
    dataset.hf_dataset.set_transform(functools.partial(_to_torch, exact=exact))
    return dataset


def _to_torch(batch: dict[str, list], exact: list[str]) -> dict[str, list]:
    """LeRobot's conversion of a batch of rows to tensors, but float64 for `exact` keys."""
    order = list(batch)
    kept = {k: [torch.tensor(v, dtype=torch.float64) for v in batch.pop(k)]
            for k in exact if k in batch}
    converted = hf_transform_to_torch(batch)
    return {k: kept[k] if k in kept else converted[k] for k in order}


def add_episode(dataset: LeRobotDataset, instruction: str,
                columns: dict[str, np.ndarray]) -> None:
    """Append one episode: `columns` maps feature keys to (T, ...) arrays."""
    for t in range(len(columns[ACTION])):
        dataset.add_frame({"task": instruction, **{k: v[t] for k, v in columns.items()}})
    dataset.save_episode()


def recompress(root: pathlib.Path, level: int = 3) -> None:
    """Re-encode a finished dataset's parquet files with zstd instead of LeRobot's snappy.

    Simulator states are float64 and barely compress under snappy; zstd stores a PickCube
    demo ~25% smaller, and every parquet reader (LeRobot's included) reads it unchanged.
    Each file is written beside itself, then renamed over it.
    """
    for path in [*root.glob(DATA_GLOB), *root.glob("meta/episodes/chunk-*/file-*.parquet")]:
        tmp = path.with_name(f".{path.name}.tmp")
        table = pq.read_table(path)
        pq.write_table(table, tmp, compression="zstd", compression_level=level,
                       use_dictionary=True)
        tmp.replace(path)


def info(root: pathlib.Path) -> dict:
    path = root / "meta" / "info.json"
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise DatasetError(f"{path} is missing; the dataset is incomplete") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise DatasetError(f"{path} is corrupt ({err})") from None


def read_parquet(path: pathlib.Path, columns: list[str] | None = None) -> pa.Table:
    """A parquet file, or a DatasetError naming it when it is missing or damaged."""
    try:
        return pq.read_table(path, columns=columns)
    except FileNotFoundError:
        raise DatasetError(f"{path} is missing; the dataset is incomplete") from None
    except (pa.ArrowException, OSError) as err:
        raise DatasetError(f"{path} is truncated or corrupt ({' '.join(str(err).split())}); "
                           "restore it or re-create the dataset") from None


def column_array(column: pa.ChunkedArray) -> np.ndarray:
    """(rows, ...) numpy array of a scalar or fixed-size-list column."""
    array = column.combine_chunks()
    if pa.types.is_fixed_size_list(array.type):
        return array.flatten().to_numpy().reshape(len(array), array.type.list_size)
    return array.to_numpy()


def state_features(root: pathlib.Path) -> list[str]:
    """Keys of the 1-D float observation features (what collection records)."""
    return [k for k, ft in info(root)["features"].items()
            if k.startswith("observation.") and ft["dtype"] == "float32"
            and len(ft["shape"]) == 1]


def read_episodes(root: pathlib.Path, meta: dict, observations: bool = True) -> list[Episode]:
    """The recorded episodes of a dataset (`meta`: its dexbench.json), in order."""
    keys = [ACTION, SIM_STATE, *(state_features(root) if observations else [])]
    files = sorted(root.glob(DATA_GLOB))
    if not files:
        raise DatasetError(f"{root} has no {DATA_GLOB}; the dataset is incomplete")
    tables = [read_parquet(f, [*keys, "episode_index"]) for f in files]
    table = pa.concat_tables(tables)
    episode = column_array(table.column("episode_index"))
    starts = np.searchsorted(episode, np.arange(len(meta["episodes"]) + 1))
    if np.any(np.diff(episode) < 0) or starts[-1] != len(episode):
        raise DatasetError(f"{root}: data rows do not match the {len(meta['episodes'])} "
                           "episodes of meta/dexbench.json; re-create the dataset")
    columns = {k: column_array(table.column(k)) for k in keys}
    out = []
    for i, record in enumerate(meta["episodes"]):
        rows = slice(starts[i], starts[i + 1])
        if rows.stop - rows.start != record["length"]:
            raise DatasetError(f"{root}: episode {i} has {rows.stop - rows.start} frames, "
                               f"meta/dexbench.json says {record['length']}")
        out.append(Episode(key=tuple(record["key"]), actions=columns[ACTION][rows],
                           states=columns[SIM_STATE][rows],
                           obs={k: columns[k][rows] for k in keys[2:]},
                           success_step=record["success_step"]))
    return out
