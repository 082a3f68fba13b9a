"""`python teleop.py task=<T> embodiment=<E> source=<...>`: teleoperated demonstrations.

Frames of human hands (a recorded keypoint file or folder of takes, a webcam through
MediaPipe, an Apple Vision Pro through avp_stream: `dexbench.teleop.sources`) are
retargeted to the embodiment (`dexbench.teleop.retarget`) and drive one environment;
`collect` records the episodes (actions + simulator states, resumable, replayable to any
preset) into `runs/datasets/<task>/<embodiment>/<name>/`. Headless, each kept episode is
also written as an MP4 into the run folder `runs/teleop/<timestamp>-<task>/videos/`.
"""

from __future__ import annotations

import json
import pathlib
import sys

from omegaconf import DictConfig

from dexbench.cli.app import Command, hydra_main, register
from dexbench.cli.collect import NoExpertError, collect_one, collect_settings
from dexbench.cli.config import ConfigError, open_run_dir
from dexbench.data.episode import Episode
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.scene import check_pair
from dexbench.eval.video import EpisodeCamera, write_mp4
from dexbench.tasks.registry import task_class
from dexbench.teleop.player import TeleopPlayer
from dexbench.teleop.sources import open_source


def check(cfg: DictConfig, overrides: list[str]) -> None:
    if not cfg.source:
        raise ConfigError("source= is required: file:<keypoints .npz or folder>, "
                          "webcam[:<index>] or avp:<ip>")
    if int(cfg.num_envs) != 1:
        raise ConfigError("teleoperation drives one environment: num_envs=1")
    if cfg.obs != "state":
        raise ConfigError("teleop records simulator states and state observations; render "
                          f"obs={cfg.obs} afterwards with `python replay.py dataset=<folder> "
                          f"obs={cfg.obs}`")
    collect_settings(cfg)
    check_pair(task_class(cfg.task), cfg.embodiment or task_class(cfg.task).default_embodiment)


def run_dir(cfg: DictConfig) -> tuple[str, str]:
    return "teleop", f"{{stamp}}-{cfg.task}"


class _Videos:
    """Each kept episode as an MP4, rendered from its recorded states."""

    def __init__(self, cfg: DictConfig, out: pathlib.Path) -> None:
        self.cfg, self.out, self.camera = cfg.video, out / "videos", None
        self.count = 0

    def __call__(self, env: DexEnv, episode: Episode) -> None:
        every = int(self.cfg.every)
        if every <= 0:
            return
        if self.camera is None:
            self.camera = EpisodeCamera(env, self.cfg.camera, int(self.cfg.width),
                                        int(self.cfg.height))
        frames = [self.camera.render_state(s) for s in episode.states[::every]]
        tag = "success" if episode.success_step >= 0 else "failure"
        write_mp4(frames, self.out / f"episode{self.count:04d}-{tag}.mp4",
                  1.0 / (env.control_dt * every))
        self.count += 1


def run(cfg: DictConfig, _prepared: None, out: pathlib.Path) -> int:
    open_run_dir(out, cfg)
    videos = _Videos(cfg, out)
    made: dict[str, DexEnv] = {}

    def player(env: DexEnv) -> TeleopPlayer:
        made["env"] = env
        return TeleopPlayer(env, open_source(str(cfg.source), tuple(env.embodiment.sides)),
                            hold_s=float(cfg.hold_s))

    try:
        stats = collect_one(cfg, player, on_episode=lambda ep: videos(made["env"], ep))
    except (FileNotFoundError, ImportError) as err:
        raise ConfigError(str(err)) from None
    except NoExpertError as err:
        raise ConfigError(str(err)) from None
    except KeyboardInterrupt:
        return 130
    print(f"{stats['task']} on {stats['embodiment']}: kept {stats['kept']} "
          f"({stats['successes']} successful of {stats['attempts']} attempts) -> "
          f"{stats.get('dataset', 'no dataset written')}; videos in {videos.out}",
          file=sys.stderr)
    print(json.dumps(stats))
    return 0 if stats["complete"] else 1


COMMAND = register(Command("teleop", run, check, run_dir))
hydra_entry = hydra_main(COMMAND)


def main(argv: list[str]) -> int:
    """Programmatic `python teleop.py ...`."""
    return COMMAND.main(argv)
