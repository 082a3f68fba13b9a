"""Run an expert on a batched env and keep its successful episodes as a dataset.

An episode ends `post_success_steps` control steps after success first holds (kept), at
the time limit without success (a time-out), when the expert says it has nothing more
to do (an optional `ended()`: a teleoperation take that ran out; a time-out too) or at a
simulator warning (a failure); finished envs go on with their next episode key. With
`keep_failures` time-outs are kept as well (success step -1), for review and tests.
Each kept episode is written whole to `<out>.partial/` at once, with the counters, so an
interrupted collection resumes where it stopped: no key is used twice and an episode cut
short is dropped. When `num_demos` are kept (or `max_attempts` episodes have finished)
the LeRobot dataset is built in the partial folder and moved to `<out>` in one rename.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import shutil
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import torch
from tqdm import tqdm

from dexbench.data.episode import Episode
from dexbench.data.features import ACTION, GROUP_OF, SIM_STATE, dataset_features, feature_key
from dexbench.data.files import digests, publish, write_json
from dexbench.data.lerobot_io import add_episode, create_dataset, read_episodes, recompress
from dexbench.data.meta import META_FILE, DatasetError, env_meta, read_meta
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.base import Expert

STATS_FILE = "collect_stats.json"


@dataclass(frozen=True)
class CollectSettings:
    num_demos: int
    max_attempts: int  # finished episodes, kept or not, before giving up
    post_success_steps: int = 10
    keep_failures: bool = False  # keep time-outs too (teleoperation review, tests)


@dataclass
class Progress:
    """Counters that survive an interruption (kept episodes are counted by their files)."""

    timeouts: int = 0
    failures: int = 0
    next_episode: list[int] = field(default_factory=list)  # per env: its next episode
    wall_time_s: float = 0.0


class Staging:
    """`<out>.partial/`: kept episodes (one file each) and counters of a collection."""

    def __init__(self, out: pathlib.Path) -> None:
        self.dir = out.with_name(out.name + ".partial")
        self.episodes = self.dir / "episodes"
        self._progress = self.dir / "progress.json"

    def open(self, recording: dict, start: Progress) -> Progress:
        """Create or reopen; an episode file cut short by a kill is deleted."""
        self.episodes.mkdir(parents=True, exist_ok=True)
        for tmp in self.episodes.glob("*.tmp"):
            tmp.unlink()
        if not self._progress.exists():
            self.save(recording, start)
            return start
        stored = json.loads(self._progress.read_text())
        if stored["recording"] != recording:
            raise DatasetError(
                f"{self.dir} holds an unfinished collection with other settings "
                f"({stored['recording']} vs now {recording}); finish it with the same "
                "settings, or choose another name=/out=")
        return Progress(**stored["progress"])

    def save(self, recording: dict, progress: Progress) -> None:
        write_json(self._progress, {"recording": recording,
                                    "progress": dataclasses.asdict(progress)})

    def load(self) -> list[Episode]:
        return [Episode.load(p) for p in sorted(self.episodes.glob("*.npz"))]


def _check_env(env: DexEnv) -> None:
    if env.cameras is not None or env.history or "proprio" not in env.groups:
        raise ValueError("collect records state observations: build the env with "
                         "obs='state' and render cameras later with replay")


def _finished(out: pathlib.Path, recording: dict) -> dict | None:
    """The metadata of a finished dataset at `out`, if there is one."""
    if not out.exists():
        return None
    if not (out / META_FILE).exists():
        raise DatasetError(f"{out} exists but is not a dexbench dataset; choose another "
                           "name=/out=")
    meta = read_meta(out)
    if meta["collection"]["recording"] != recording:
        raise DatasetError(f"{out} was collected with other settings "
                           f"({meta['collection']['recording']} vs now {recording}); "
                           "choose another name=/out=")
    return meta


class _Frames:
    """Every env's frames, step by step, until its episode ends."""

    def __init__(self) -> None:
        self.steps: list[dict[str, np.ndarray]] = []
        self.base = 0  # global index of steps[0]

    def add(self, frame: dict[str, np.ndarray]) -> None:
        self.steps.append(frame)

    def episode(self, env: int, start: int, stop: int) -> dict[str, np.ndarray]:
        rows = self.steps[start - self.base:stop - self.base]
        return {k: np.stack([r[k][env] for r in rows]) for k in rows[0]}

    def drop_before(self, step: int) -> None:
        del self.steps[:step - self.base]
        self.base = step


def collect(env: DexEnv, expert: Expert, out: pathlib.Path, settings: CollectSettings,
            config: dict, on_episode: Callable[[Episode], None] | None = None,
            progress: bool = True) -> dict:
    """Collect (or resume, or extend) the dataset at `out`; return its statistics.

    `config` is the resolved command config, stored with the dataset; `on_episode` is
    called with each kept episode once it is safely on disk.
    """
    _check_env(env)
    started = time.perf_counter()
    meta = env_meta(env)
    recording = {"config_hash": meta["config_hash"],
                 "post_success_steps": settings.post_success_steps}
    if settings.keep_failures:
        recording["keep_failures"] = True
    staging = Staging(out)
    finished = _finished(out, recording)
    if finished and not staging.dir.exists() and len(finished["episodes"]) >= settings.num_demos:
        return json.loads((out / STATS_FILE).read_text())
    start = Progress(**finished["collection"]["progress"]) if finished else Progress()
    resumed = staging.dir.exists()
    prog = staging.open(recording, start)
    kept = {ep.key: ep for ep in staging.load()}
    if resumed:  # an earlier run's counters go on (also an expert changed since)
        print(f"resuming {staging.dir}: {len(kept)} kept of "
              f"{_successes(kept.values()) + prog.timeouts + prog.failures} attempts so far; "
              "delete it to start over", file=sys.stderr)
    for ep in read_episodes(out, finished) if finished else []:
        if ep.key not in kept:
            ep.save(staging.episodes)
            kept[ep.key] = ep
    bar = tqdm(total=settings.num_demos, initial=min(len(kept), settings.num_demos),
               desc=f"collect {env.task.name} {env.embodiment.name}", unit="demo",
               disable=not progress)
    with bar:
        _run(env, expert, settings, staging, recording, prog, kept, on_episode, bar, started)
    prog.wall_time_s += time.perf_counter() - started
    episodes = sorted(kept.values(), key=lambda e: e.key)
    stats = _stats(meta, settings, episodes, prog, type(expert).__name__)
    if not episodes:
        staging.save(recording, prog)
        write_json(staging.dir / STATS_FILE, stats)
        return stats
    full = {**meta, "config": config, "collection": {
        "recording": recording, "progress": dataclasses.asdict(prog),
        "expert": stats["expert"], "attempts": stats["attempts"],
        "successes": stats["successes"], "timeouts": prog.timeouts,
        "failures": prog.failures}}
    return _assemble(out, staging, full, episodes, stats)


def _run(env: DexEnv, expert: Expert, settings: CollectSettings, staging: Staging,
         recording: dict, prog: Progress, kept: dict, on_episode, bar, started: float) -> None:
    n = env.num_envs
    prog.next_episode += [0] * (n - len(prog.next_episode))
    for key in kept:  # keys in files outrank counters a kill left behind
        if key[0] == env.seed and key[1] < n:
            prog.next_episode[key[1]] = max(prog.next_episode[key[1]], key[2] + 1)

    def attempts() -> int:
        return _successes(kept.values()) + prog.timeouts + prog.failures

    def more() -> bool:
        return len(kept) < settings.num_demos and attempts() < settings.max_attempts

    def begin(ids: np.ndarray) -> dict[str, torch.Tensor]:
        keys = [(env.seed, int(i), prog.next_episode[i]) for i in ids]
        for i in ids:
            prog.next_episode[i] += 1
        obs = env.reset_to(ids, keys)
        expert.reset(torch.as_tensor(ids))
        return obs

    if not more():
        return
    low, high = env.action_low.float(), env.action_high.float()
    obs = begin(np.arange(n))
    frames, step = _Frames(), 0
    start = np.zeros(n, dtype=np.int64)  # step at which each env's episode began
    success_at = np.full(n, -1)  # episode length when success first held
    while True:
        state = env.sim_state().numpy()  # the state the observations describe
        action = torch.clamp(torch.as_tensor(expert.act()).float(), low, high)
        frames.add({SIM_STATE: state, ACTION: action.numpy(),
                    **{feature_key(g): v.numpy() for g, v in obs.items()}})
        obs, _, success, truncated, info = env.step(action)
        step += 1
        length = step - start
        first = success.numpy() & (success_at < 0)
        success_at[first] = length[first]
        succeeded = success_at >= 0
        failed = info["sim_warnings"].numpy() > 0
        gave_up = expert.ended() if hasattr(expert, "ended") else np.zeros(n, dtype=bool)
        timeout = (truncated.numpy() | gave_up) & ~succeeded
        ended = failed | timeout | (succeeded & (
            (length - success_at >= settings.post_success_steps) | truncated.numpy()))
        for i in np.flatnonzero(ended):
            if not more():
                break
            ep = None
            if failed[i]:
                prog.failures += 1
            elif timeout[i] and not settings.keep_failures:
                prog.timeouts += 1
            else:
                prog.timeouts += int(bool(timeout[i]))
                cols = frames.episode(i, start[i], step)
                ep = Episode(key=tuple(int(k) for k in env.episode_keys[i]),
                             actions=cols.pop(ACTION), states=cols.pop(SIM_STATE), obs=cols,
                             success_step=int(success_at[i]) if succeeded[i] else -1)
                ep.save(staging.episodes)
                kept[ep.key] = ep
            staging.save(recording, dataclasses.replace(
                prog, wall_time_s=prog.wall_time_s + time.perf_counter() - started))
            bar.update(int(ep is not None))
            bar.set_postfix(attempts=attempts(),
                            rate=f"{_successes(kept.values()) / attempts():.2f}")
            if ep is not None and on_episode is not None:
                on_episode(ep)
        if not more():
            return
        restart = np.flatnonzero(ended)
        if len(restart):
            obs = begin(restart)
            start[restart], success_at[restart] = step, -1
            frames.drop_before(int(start.min()))


def _successes(episodes) -> int:
    """Kept episodes in which success held (all of them unless `keep_failures`)."""
    return sum(ep.success_step >= 0 for ep in episodes)


def _stats(meta: dict, settings: CollectSettings, episodes: list[Episode], prog: Progress,
           expert: str) -> dict:
    successes = _successes(episodes)
    attempts = successes + prog.timeouts + prog.failures
    lengths = [ep.length for ep in episodes]
    raw = 0
    if episodes:
        ep = episodes[0]
        raw = ep.actions[0].nbytes + ep.states[0].nbytes + sum(
            v[0].nbytes for v in ep.obs.values())
    return {
        "task": meta["task"],
        "embodiment": meta["embodiment"],
        "expert": expert,
        "num_demos": settings.num_demos,
        "complete": len(episodes) >= settings.num_demos,
        "attempts": attempts,
        "successes": successes,
        "kept": len(episodes),
        "timeouts": prog.timeouts,
        "failures": prog.failures,
        "success_rate": round(successes / attempts, 4) if attempts else 0.0,
        "mean_episode_length": round(float(np.mean(lengths)), 2) if lengths else 0.0,
        "frames": int(sum(lengths)),
        "raw_bytes_per_step": int(raw),
        "wall_time_s": round(prog.wall_time_s, 2),
    }


def _assemble(out: pathlib.Path, staging: Staging, meta: dict, episodes: list[Episode],
              stats: dict) -> dict:
    started = time.perf_counter()
    build = staging.dir / "dataset"
    shutil.rmtree(build, ignore_errors=True)
    first = episodes[0]
    shapes = {GROUP_OF[k]: v.shape[1:] for k, v in first.obs.items()}
    features = dataset_features(shapes, meta["action_layout"]["actuators"],
                                meta["sim_state"]["size"], meta["proprio_joints"])
    dataset = create_dataset(build, features, meta["fps"], meta["embodiment"])
    for ep in episodes:
        add_episode(dataset, meta["instruction"], {ACTION: ep.actions, SIM_STATE: ep.states,
                                                   **ep.obs})
    dataset.finalize()
    recompress(build)
    files = digests(build, META_FILE)
    meta = {**meta, "repo_id": dataset.repo_id, "files": files, "episodes": [
        {"episode_index": i, "key": list(ep.key), "length": ep.length,
         "success": ep.success_step >= 0,
         "success_step": ep.success_step, "task": meta["task"],
         "instruction": meta["instruction"], "embodiment": meta["embodiment"]}
        for i, ep in enumerate(episodes)]}
    write_json(build / META_FILE, meta)
    data_bytes = sum(f.stat().st_size for f in (build / "data").rglob("*.parquet"))
    stats = {**stats, "dataset": str(out),
             "bytes_per_step": round(data_bytes / stats["frames"], 1),
             "dataset_bytes": sum(f.stat().st_size for f in build.rglob("*") if f.is_file()),
             "wall_time_s": round(stats["wall_time_s"] + time.perf_counter() - started, 2)}
    write_json(build / STATS_FILE, stats)
    publish(build, out, staging.dir / "previous")
    shutil.rmtree(staging.dir)
    return stats
