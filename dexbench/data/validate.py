"""Check a dexbench dataset: files, schema, counts, values, and the code it needs.

Missing, truncated or corrupt files (also damage that still parses: every file's
checksum is recorded when it is written), features that disagree with `meta/info.json`,
frame or episode counts that do not add up, non-finite values and actions outside the
recorded actuator ranges are errors. A config hash that differs from what the current
code builds is a warning naming what changed (states then no longer replay to the
recorded observations).
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa

from dexbench.data.features import ACTION, SIM_STATE
from dexbench.data.lerobot_io import column_array, info, read_parquet
from dexbench.data.meta import (
    DatasetError,
    code_changes,
    damaged_files,
    env_from_config,
    read_meta,
)

ACTION_TOLERANCE = 1e-5  # float32 actions against float64 actuator ranges


@dataclass
class Report:
    root: pathlib.Path
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    summary: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.errors


def validate_dataset(root: pathlib.Path, check_code: bool = True, nthread: int = 0) -> Report:
    """Every check on the dataset at `root`; `check_code` rebuilds its env to compare."""
    report = Report(root)
    try:
        meta, tables = _files(root, report)
        if tables:
            _contents(root, meta, tables, report)
        if check_code:
            env = env_from_config(meta["env_config"], num_envs=1, nthread=nthread)
            report.warnings += [f"recorded with other code: {c}"
                                for c in code_changes(meta, env)]
    except DatasetError as err:
        report.errors.append(str(err))
    return report


def _files(root: pathlib.Path, report: Report) -> tuple[dict, list[pa.Table]]:
    """Metadata, and every data file read whole (corruption shows when decoding)."""
    if not root.is_dir():
        raise DatasetError(f"{root} is not a dataset folder")
    meta, inf = read_meta(root), info(root)
    for name in ("meta/tasks.parquet", "meta/stats.json"):
        if not (root / name).is_file():
            report.errors.append(f"{root / name} is missing; the dataset is incomplete")
    episode_files = sorted(root.glob("meta/episodes/chunk-*/file-*.parquet"))
    if not episode_files:
        report.errors.append(f"{root}/meta/episodes has no parquet files; the dataset is "
                             "incomplete")
    tables, data_files = [], set()
    for path in episode_files:
        try:
            episodes = read_parquet(path, ["data/chunk_index", "data/file_index"])
        except DatasetError as err:
            report.errors.append(str(err))
            continue
        chunks, files = (column_array(episodes.column(c)) for c in episodes.column_names)
        data_files |= {inf["data_path"].format(chunk_index=c, file_index=f)
                       for c, f in zip(chunks, files, strict=True)}
    for name in sorted(data_files):
        try:
            tables.append(read_parquet(root / name))
        except DatasetError as err:
            report.errors.append(str(err))
    if not report.errors:
        report.errors += damaged_files(root, meta)
    return meta, [] if report.errors else tables


def _contents(root: pathlib.Path, meta: dict, tables: list[pa.Table], report: Report) -> None:
    inf = info(root)
    features = inf["features"]
    errors = report.errors
    expected = {ACTION: ("float32", [len(meta["action_layout"]["actuators"])]),
                SIM_STATE: ("float64", [meta["sim_state"]["size"]]),
                "observation.state": ("float32", [len(meta["proprio_joints"])])}
    for key, (dtype, shape) in expected.items():
        ft = features.get(key)
        if ft is None or ft["dtype"] != dtype or list(ft["shape"]) != shape:
            errors.append(f"feature {key}: expected {dtype} {shape} from meta/dexbench.json, "
                          f"meta/info.json has {ft and (ft['dtype'], ft['shape'])}")
    table = pa.concat_tables(tables)
    for key, ft in features.items():
        if ft["dtype"] == "video":
            continue
        if key not in table.column_names:
            errors.append(f"feature {key} has no column in the data files")
            continue
        typ = table.schema.field(key).type
        if len(ft["shape"]) == 1 and ft["shape"][0] > 1 and ft["dtype"] != "image" and (
                not pa.types.is_fixed_size_list(typ) or typ.list_size != ft["shape"][0]
                or typ.value_type != pa.from_numpy_dtype(np.dtype(ft["dtype"]))):
            errors.append(f"feature {key}: data column is {typ}, meta/info.json says "
                          f"{ft['dtype']} {ft['shape']}")
    if errors:
        return
    cols = {k: column_array(table.column(k)) for k in
            (ACTION, SIM_STATE, "episode_index", "frame_index", "index", "timestamp")}
    records = meta["episodes"]
    lengths = np.bincount(cols["episode_index"], minlength=len(records))
    if table.num_rows != inf["total_frames"]:
        errors.append(f"{table.num_rows} frames in the data files, meta/info.json says "
                      f"{inf['total_frames']}")
    if not (len(records) == inf["total_episodes"] == len(lengths)):
        errors.append(f"episode counts disagree: meta/dexbench.json {len(records)}, "
                      f"meta/info.json {inf['total_episodes']}, data {len(lengths)}")
    elif any(r["length"] != n for r, n in zip(records, lengths, strict=True)):
        errors.append("episode lengths in the data differ from meta/dexbench.json")
    if len({tuple(r["key"]) for r in records}) != len(records):
        errors.append("meta/dexbench.json lists an episode key twice")
    if not np.array_equal(cols["index"], np.arange(table.num_rows)):
        errors.append("the index column is not 0..N-1 in order")
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    frame = np.arange(table.num_rows) - np.repeat(starts, lengths)
    if not np.array_equal(cols["frame_index"], frame):
        errors.append("frame_index does not count 0..T-1 within each episode")
    if not np.allclose(cols["timestamp"], frame / inf["fps"], atol=1e-4):
        errors.append(f"timestamps are not frame_index / fps ({inf['fps']})")
    for key in (ACTION, SIM_STATE):
        if not np.isfinite(cols[key]).all():
            errors.append(f"{key} holds NaN or inf")
    layout = meta["action_layout"]
    low, high = np.asarray(layout["low"]), np.asarray(layout["high"])
    outside = ((cols[ACTION] < low - ACTION_TOLERANCE)
               | (cols[ACTION] > high + ACTION_TOLERANCE)).any(axis=0)
    if outside.any():
        names = [a for a, o in zip(layout["actuators"], outside, strict=True) if o]
        errors.append(f"actions outside the actuator ranges of the layout: {names}")
    report.summary = {"task": meta["task"], "embodiment": meta["embodiment"],
                      "episodes": len(records), "frames": table.num_rows,
                      "config_hash": meta["config_hash"],
                      "features": {k: [ft["dtype"], list(ft["shape"])]
                                   for k, ft in features.items()}}
