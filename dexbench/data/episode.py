"""One recorded demonstration, and its file while a collection is unfinished."""

from __future__ import annotations

import os
import pathlib
from dataclasses import dataclass

import numpy as np


@dataclass
class Episode:
    """Frames 0..T-1: frame t holds the observations and simulator state before action t.

    `key` (seed, env, episode) replays the episode's reset (`DexEnv.reset_to`); `actions`
    are float32 exactly as applied (within the actuator ranges); `states` are float64
    `DexEnv.sim_state` rows; `obs` maps feature keys to recorded observations;
    `success_step` counts the actions after which success first held.
    """

    key: tuple[int, int, int]
    actions: np.ndarray
    states: np.ndarray
    obs: dict[str, np.ndarray]
    success_step: int

    @property
    def length(self) -> int:
        return len(self.actions)

    @property
    def file_name(self) -> str:
        return "episode-{}-{}-{}.npz".format(*self.key)

    def save(self, folder: pathlib.Path) -> pathlib.Path:
        """Write `<folder>/<file_name>` whole or not at all (temp file, then rename)."""
        path = folder / self.file_name
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as f:
            np.savez(f, key=np.asarray(self.key, np.int64), actions=self.actions,
                     states=self.states, success_step=np.int64(self.success_step),
                     **{f"obs/{k}": v for k, v in self.obs.items()})
        os.replace(tmp, path)
        return path

    @classmethod
    def load(cls, path: pathlib.Path) -> Episode:
        with np.load(path) as f:
            return cls(key=tuple(int(k) for k in f["key"]), actions=f["actions"],
                       states=f["states"], success_step=int(f["success_step"]),
                       obs={k.removeprefix("obs/"): f[k] for k in f.files
                            if k.startswith("obs/")})
