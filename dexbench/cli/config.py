"""Compose the Hydra config tree under `conf/` from `key=value` overrides.

The entry points use Hydra's compose API rather than `@hydra.main` so they can take a
sub-command (`bench.py sim ...`, `python -m dexbench inspect ...`) and keep outputs in
our own `runs/` layout.
"""

from __future__ import annotations

import datetime as dt
import os
import pathlib
import sys

import yaml
from hydra import compose, initialize_config_dir
from hydra.errors import HydraException
from omegaconf import DictConfig, ListConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from dexbench.envs.arena import PhysicsOptions
from dexbench.envs.observations import resolve_preset
from dexbench.envs.variation import PhysicalVariation, VisualVariation

CONF_DIR = pathlib.Path(__file__).resolve().parents[2] / "conf"


class ConfigError(ValueError):
    """Bad command-line overrides."""


def load_config(name: str, overrides: list[str]) -> DictConfig:
    """The resolved config `conf/<name>.yaml` with overrides applied."""
    bad = [o for o in overrides if "=" not in o]
    if bad:
        raise ConfigError(f"arguments must be key=value overrides, got {bad}")
    try:
        with initialize_config_dir(str(CONF_DIR), version_base="1.3"):
            cfg = compose(config_name=name, overrides=overrides)
    except (HydraException, OmegaConfBaseException) as err:
        raise ConfigError(" ".join(str(err).split())) from None
    OmegaConf.resolve(cfg)
    return cfg


def positive_int(cfg: DictConfig, key: str) -> int:
    """`cfg.<key>` as an int >= 1, or a ConfigError saying so."""
    value = OmegaConf.select(cfg, key)
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ConfigError(f"{key} must be a whole number >= 1, got {value!r}; pass e.g. "
                          f"{key}=1")
    return value


def obs_of(cfg: DictConfig) -> str | list[str]:
    """`cfg.obs` as `make_env` takes it: a known preset or a list of known groups."""
    obs = list(cfg.obs) if isinstance(cfg.obs, ListConfig) else str(cfg.obs)
    try:
        resolve_preset(obs)
    except ValueError as err:
        raise ConfigError(str(err)) from None
    return obs


def env_kwargs(cfg: DictConfig) -> dict:
    """Keyword arguments of `make_env` from the common environment keys, checked."""
    physics = PhysicsOptions(timestep=float(cfg.sim.timestep),
                             control_hz=float(cfg.sim.control_hz))
    obs = obs_of(cfg)
    cam = cfg.camera
    return dict(task=cfg.task, embodiment=cfg.embodiment, num_envs=positive_int(cfg, "num_envs"),
                seed=int(cfg.seed), obs=obs, backend=cfg.sim.backend,
                nthread=int(cfg.sim.nthread), physics=physics,
                cameras=list(cam.names) if cam.names else None,
                image_size=(int(cam.width), int(cam.height)), num_points=int(cam.num_points),
                renderer=cam.renderer, shadows=bool(cam.shadows),
                visual=VisualVariation(**OmegaConf.to_container(cfg.visual)),
                physical=PhysicalVariation(**{
                    k: tuple(v) if isinstance(v, list) else v
                    for k, v in OmegaConf.to_container(cfg.physical).items()}))


def runs_root() -> pathlib.Path:
    """Where outputs go: `$DEXBENCH_RUNS_DIR`, else `./runs`."""
    return pathlib.Path(os.environ.get("DEXBENCH_RUNS_DIR", "runs"))


def new_run_dir(kind: str, label: str, cfg: DictConfig) -> pathlib.Path:
    """Create `runs/<kind>/<timestamp>-<label>/` holding the resolved config."""
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
    path = runs_root() / kind / f"{stamp}-{label}"
    path.mkdir(parents=True, exist_ok=False)
    write_atomic(path / "config.yaml", yaml.safe_dump(OmegaConf.to_container(cfg)))
    (path / "command.txt").write_text(" ".join(sys.argv) + "\n")
    return path


def write_atomic(path: pathlib.Path, text: str) -> None:
    """Write via a temp file and rename, so readers never see half a file."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    tmp.replace(path)
