"""`episodes.jsonl`: one line per finished episode, written and synced as it ends, so an
interrupted evaluation loses at most the episodes still running."""

from __future__ import annotations

import json
import os
import pathlib
from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class EpisodeRecord:
    task: str
    episode: int  # evaluation episode index (its key: `seeds.eval_keys`)
    seed: int
    success: bool  # the task's success predicate held at some step
    steps: int  # control steps until success or the time limit
    time_s: float  # wall time from its reset to its end (shared with the batch)
    sim_warnings: int
    embodiment: str


class EpisodeLog:
    """Append-only JSON lines; a line cut short by a kill is dropped on load."""

    def __init__(self, path: pathlib.Path) -> None:
        self.path = path

    def load(self) -> list[EpisodeRecord]:
        """Finished episodes, first record of each (task, episode); repairs a torn tail."""
        if not self.path.exists():
            return []
        data = self.path.read_bytes()
        whole = data[:data.rfind(b"\n") + 1]
        if len(whole) != len(data):
            with open(self.path, "r+b") as f:
                f.truncate(len(whole))
        out: dict[tuple[str, int], EpisodeRecord] = {}
        for number, line in enumerate(whole.decode().splitlines(), 1):
            try:
                rec = EpisodeRecord(**json.loads(line))
            except (ValueError, TypeError) as err:
                raise ValueError(f"{self.path} line {number} is not an episode record "
                                 f"({err}); move the file away to start over") from None
            out.setdefault((rec.task, rec.episode), rec)
        return list(out.values())

    def append(self, record: EpisodeRecord) -> None:
        with open(self.path, "a") as f:
            f.write(json.dumps(asdict(record)) + "\n")
            f.flush()
            os.fsync(f.fileno())
