"""The config tree under `conf/` and the checks every command shares.

The entry points are Hydra mains (`dexbench/cli/app.py`); `load_config` composes the
same tree with Hydra's compose API for the programmatic forms (`<module>.main(argv)`).
`conf/` sits at the repository root and is installed as `dexbench/conf`.
"""

from __future__ import annotations

import os
import pathlib
import sys

import yaml
from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from hydra.errors import HydraException
from omegaconf import DictConfig, ListConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from dexbench.cli.schema import physics_options
from dexbench.envs.observations import resolve_preset
from dexbench.envs.variation import PhysicalVariation, VisualVariation


def _conf_dir() -> pathlib.Path:
    """The repository's `conf/` in a checkout, else the installed copy `dexbench/conf`."""
    package = pathlib.Path(__file__).resolve().parents[1]
    checkout = package.parent / "conf"
    return checkout if (checkout / "config.yaml").exists() else package / "conf"


CONF_DIR = _conf_dir()


class ConfigError(ValueError):
    """Bad command-line overrides."""


def spread_device(device: str, job_num: int | None, gpus: int) -> str:
    """`auto` for job `job_num` of a sweep on a machine with `gpus` GPUs: the job's own
    GPU, `cuda:<job_num mod gpus>`; anything else unchanged."""
    if device != "auto" or job_num is None or gpus < 2:
        return device
    return f"cuda:{job_num % gpus}"


def job_device(device: str) -> str:
    """`device` for this process: in a `-m` job with several GPUs, `auto` becomes the job's
    own GPU, so that a launcher's parallel jobs (trainings, evaluations) spread over the
    GPUs instead of all landing on the first."""
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode

    if device != "auto" or not HydraConfig.initialized():
        return device
    hc = HydraConfig.get()
    if hc.mode != RunMode.MULTIRUN:
        return device
    import torch  # here: the light commands that read the config need no torch

    gpus = torch.cuda.device_count() if torch.cuda.is_available() else 0
    return spread_device(device, hc.job.get("num"), gpus)


def load_config(name: str, overrides: list[str]) -> DictConfig:
    """The resolved config `conf/<name>.yaml` with overrides applied."""
    bad = [o for o in overrides if "=" not in o]
    if bad:
        raise ConfigError(f"arguments must be key=value overrides, got {bad}")
    GlobalHydra.instance().clear()  # a Hydra main run earlier in this process
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
    try:
        physics = physics_options(cfg.sim)
        physics.decimation  # noqa: B018  (checks timestep against control_hz)
    except ValueError as err:
        raise ConfigError(f"sim: {err}") from None
    obs = obs_of(cfg)
    cam = cfg.camera
    return dict(task=cfg.task, embodiment=cfg.embodiment, num_envs=positive_int(cfg, "num_envs"),
                seed=int(cfg.seed), obs=obs, backend=cfg.sim.backend,
                nthread=int(cfg.sim.nthread), physics=physics,
                cameras=list(cam.names) if cam.names else None,
                image_size=(int(cam.width), int(cam.height)), num_points=int(cam.num_points),
                cloud_device=cloud_device_of(cfg), renderer=renderer_of(cfg),
                shadows=bool(cam.shadows),
                visual=VisualVariation(**OmegaConf.to_container(cfg.visual)),
                physical=PhysicalVariation(**{
                    k: tuple(v) if isinstance(v, list) else v
                    for k, v in OmegaConf.to_container(cfg.physical).items()}))


def cloud_device_of(cfg: DictConfig) -> str | None:
    """`camera.cloud_device`: null (the renderer's device), cpu or cuda, checked; in a
    `-m` sweep on several GPUs, cuda is the job's own GPU (as `device=auto`), so that
    parallel replays and evaluations do not all compute their clouds on the first."""
    device = cfg.camera.get("cloud_device")
    if device is None:
        return None
    if device not in ("cpu", "cuda"):
        raise ConfigError(f"camera.cloud_device={device}: use null, cpu or cuda")
    import torch  # here, as above

    if device == "cuda" and not torch.cuda.is_available():
        raise ConfigError("camera.cloud_device=cuda but no CUDA device is visible: "
                          "use camera.cloud_device=null")
    if device == "cuda":
        own = job_device("auto")
        return "cuda" if own == "auto" else own
    return device


def renderer_of(cfg: DictConfig) -> str:
    """`camera.renderer`, with `auto` (and a config from before it) following the backend."""
    renderer = str(cfg.camera.get("renderer", "auto"))
    if renderer == "auto":
        return "warp" if cfg.sim.backend == "warp" else "cpu"
    return renderer


def runs_root() -> pathlib.Path:
    """Where outputs go: `$DEXBENCH_RUNS_DIR`, else `./runs`."""
    return pathlib.Path(os.environ.get("DEXBENCH_RUNS_DIR", "runs"))


def dataset_path(task: str, embodiment: str, name: str) -> pathlib.Path:
    """`runs/datasets/<task>/<embodiment>/<name>`: where `collect.py` writes a dataset and
    `train.py` and `rl.py` look for one by default."""
    return runs_root() / "datasets" / task / embodiment / name


def open_run_dir(path: pathlib.Path, cfg: DictConfig) -> pathlib.Path:
    """The run folder Hydra made (or, called without Hydra, make it) with the resolved
    config and the command line."""
    path.mkdir(parents=True, exist_ok=True)
    write_atomic(path / "config.yaml", yaml.safe_dump(OmegaConf.to_container(cfg, resolve=True)))
    (path / "command.txt").write_text(" ".join(sys.argv) + "\n")
    return path


def default_embodiment(cfg: DictConfig) -> str:
    """`embodiment`, or the task's default; a label only (a bad name fails later)."""
    if cfg.get("embodiment"):
        return str(cfg.embodiment)
    from dexbench.tasks.registry import TASKS

    task = TASKS.get(str(cfg.task))
    return task.default_embodiment if task is not None else "default"


def write_atomic(path: pathlib.Path, text: str) -> None:
    """Write via a temp file and rename, so readers never see half a file."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    tmp.replace(path)
