"""Demonstrations as flat arrays for training: every frame of every episode, in order.

Read straight from a dexbench LeRobot v3 dataset's parquet files (only the columns a
policy needs, no image decoding, no per-frame Python; the files are first checked against
the checksums recorded when they were written), or from a `.npz` written by
`Demos.save` (point clouds at 16 bits: a compact copy to ship to another machine).
Training windows and the train/validation split are built from episode boundaries.
"""

from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from dexbench.data.features import ACTION, GROUP_KEYS
from dexbench.data.meta import DatasetError, read_meta, verify_files

DATA_GLOB = "data/chunk-*/file-*.parquet"
HALF_PRECISION = ("pointcloud",)


@dataclass
class Demos:
    """`obs` maps observation groups to (frames, ...) float32 arrays; `episode_ends` are
    the exclusive end frame of each episode; `meta` is the dataset's dexbench.json."""

    meta: dict
    actions: np.ndarray
    obs: dict[str, np.ndarray]
    episode_ends: np.ndarray
    source: str

    @property
    def num_episodes(self) -> int:
        return len(self.episode_ends)

    def save(self, path: pathlib.Path) -> None:
        """Write a compact copy (temp file, then rename)."""
        tmp = path.with_name(f".{path.name}.tmp.npz")
        arrays = {f"obs/{k}": v.astype(np.float16) if k in HALF_PRECISION else v
                  for k, v in self.obs.items()}
        np.savez(tmp, meta=np.array(json.dumps(self.meta)), actions=self.actions,
                 episode_ends=self.episode_ends, source=np.array(self.source), **arrays)
        tmp.replace(path)

    @classmethod
    def load(cls, path: pathlib.Path) -> Demos:
        try:
            with np.load(path) as f:
                return cls(meta=json.loads(str(f["meta"])), actions=f["actions"],
                           episode_ends=f["episode_ends"], source=str(f["source"]),
                           obs={k.removeprefix("obs/"): f[k].astype(np.float32)
                                for k in f.files if k.startswith("obs/")})
        except (OSError, KeyError, ValueError) as err:
            raise DatasetError(f"{path} is not a demonstration array file written by "
                               f"Demos.save ({err})") from None


def _column(table: pa.Table, key: str, shape: list[int]) -> np.ndarray:
    array = table.column(key).combine_chunks()
    while pa.types.is_list(array.type) or pa.types.is_fixed_size_list(array.type) or \
            pa.types.is_large_list(array.type):
        array = array.flatten()
    return array.to_numpy(zero_copy_only=False).reshape(len(table), *shape)


def load_demos(root: pathlib.Path, groups: list[str]) -> Demos:
    """The action and the observation `groups` of every frame of the dataset at `root`."""
    meta = read_meta(root)
    verify_files(root, meta)
    features = json.loads((root / "meta" / "info.json").read_text())["features"]
    missing = [g for g in groups if GROUP_KEYS[g] not in features]
    if missing:
        raise DatasetError(f"{root} has no {missing} observations (it has "
                           f"{sorted(k for k in features if k.startswith('observation.'))})")
    files = sorted(root.glob(DATA_GLOB))
    if not files:
        raise DatasetError(f"{root} has no {DATA_GLOB}; the dataset is incomplete")
    keys = [ACTION, *(GROUP_KEYS[g] for g in groups)]
    try:
        table = pa.concat_tables([pq.read_table(f, columns=[*keys, "episode_index"])
                                  for f in files])
    except (pa.ArrowException, OSError) as err:
        raise DatasetError(f"{root}: cannot read its data files ({err}); run "
                           f"`python -m dexbench validate dataset={root}`") from None
    episode = table.column("episode_index").to_numpy()
    if np.any(np.diff(episode) < 0):
        raise DatasetError(f"{root}: frames are not ordered by episode; re-create it")
    ends = np.searchsorted(episode, np.arange(len(meta["episodes"])), side="right")
    lengths = np.diff(np.concatenate([[0], ends]))
    if ends[-1] != len(episode) or any(
            int(n) != r["length"] for n, r in zip(lengths, meta["episodes"], strict=True)):
        raise DatasetError(f"{root}: data rows do not match meta/dexbench.json; re-create it")
    columns = {k: _column(table, k, features[k]["shape"]).astype(np.float32) for k in keys}
    return Demos(meta=meta, actions=columns[ACTION],
                 obs={g: columns[GROUP_KEYS[g]] for g in groups},
                 episode_ends=ends.astype(np.int64), source=str(root))


def available_groups(root: pathlib.Path) -> list[str]:
    """Observation groups a dataset folder (or Demos .npz) holds."""
    if root.suffix == ".npz":
        return sorted(Demos.load(root).obs)
    features = json.loads((root / "meta" / "info.json").read_text())["features"]
    return [g for g, k in GROUP_KEYS.items() if k in features]


def windows(episode_ends: np.ndarray, n_obs_steps: int,
            horizon: int) -> tuple[np.ndarray, np.ndarray]:
    """Frame indices of each training sample: observations t-To+1..t (the first frame
    repeated before an episode starts) and actions t..t+H-1 (the last repeated after it
    ends); one sample per frame t."""
    starts = np.concatenate([[0], episode_ends[:-1]])
    lengths = episode_ends - starts
    first = np.repeat(starts, lengths)[:, None]
    last = np.repeat(episode_ends - 1, lengths)[:, None]
    t = np.arange(int(episode_ends[-1]))[:, None]
    obs = np.clip(t + np.arange(1 - n_obs_steps, 1), first, last)
    act = np.clip(t + np.arange(horizon), first, last)
    return obs, act


def split_episodes(num_episodes: int, val_fraction: float,
                   seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Train and validation episode indices; at least one of each when there are two."""
    if not 0.0 <= val_fraction < 1.0:
        raise ValueError(f"val_fraction must lie in [0, 1), got {val_fraction}")
    order = np.random.default_rng(seed).permutation(num_episodes)
    n_val = min(num_episodes - 1, max(1 if val_fraction > 0 else 0,
                                      round(val_fraction * num_episodes)))
    return np.sort(order[n_val:]), np.sort(order[:n_val])


def episode_frames(episode_ends: np.ndarray, episodes: np.ndarray) -> np.ndarray:
    """Frame indices of the given episodes."""
    starts = np.concatenate([[0], episode_ends[:-1]])
    if len(episodes) == 0:
        return np.zeros(0, dtype=np.int64)
    return np.concatenate([np.arange(starts[e], episode_ends[e]) for e in episodes])
