"""Dataset-level metadata (`meta/dexbench.json`): what was simulated, with what code.

The env config is read off the environment itself (task, embodiment, physics options,
visual and physical variation), so it is exactly what ran; its hash also covers a digest
of the compiled model, which changes whenever robot models, task objects or scene code
do. `code_changes` rebuilds the env from a stored config and says what differs now.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
import json
import pathlib
import platform
from typing import Any

import mujoco
import numpy as np

from dexbench.data.files import file_digest
from dexbench.envs.arena import PhysicsOptions
from dexbench.envs.dex_env import STATE_SPEC, DexEnv
from dexbench.envs.variation import PhysicalVariation, VisualVariation
from dexbench.sim.backend import state_layout
from dexbench.tasks.registry import make_env

FORMAT = "dexbench-demonstrations/1"
META_FILE = pathlib.Path("meta/dexbench.json")
REQUIRED = ("task", "embodiment", "instruction", "env_config", "model_digest", "config_hash",
            "action_layout", "proprio_joints", "sim_state", "fps", "episodes", "files")
VERSIONED = ("dexbench", "mujoco", "lerobot", "torch")


class DatasetError(ValueError):
    """A dataset that is missing, corrupt, incomplete or recorded with other code."""


def as_json(obj: Any) -> Any:
    """JSON's view of a value (tuples become lists), to compare stored and current."""
    return json.loads(json.dumps(obj))


def env_config(env: DexEnv) -> dict:
    """The settings that decide what an env simulates (not cameras, batch or seed)."""
    return as_json({
        "task": env.task.name,
        "embodiment": env.embodiment.name,
        "physics": dataclasses.asdict(env.physics),
        "visual": dataclasses.asdict(env.variation.visual),
        "physical": dataclasses.asdict(env.variation.physical),
    })


def env_from_config(config: dict, **kwargs) -> DexEnv:
    """An env built from a stored `env_config` (plus e.g. num_envs, obs, cameras)."""
    try:
        physical = {k: tuple(v) if isinstance(v, list) else v
                    for k, v in config["physical"].items()}
        return make_env(config["task"], config["embodiment"],
                        physics=PhysicsOptions(**config["physics"]),
                        visual=VisualVariation(**config["visual"]),
                        physical=PhysicalVariation(**physical), **kwargs)
    except (KeyError, TypeError) as err:
        raise DatasetError(f"the recorded env config no longer fits the code ({err}); "
                           "use the dexbench version the dataset names, or re-collect") from None


def model_digest(model: mujoco.MjModel) -> str:
    """sha256 of the compiled model (MJB bytes)."""
    buffer = np.zeros(mujoco.mj_sizeModel(model), np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    return hashlib.sha256(buffer.tobytes()).hexdigest()


def config_hash(config: dict, digest: str) -> str:
    """Stable hash of an env config and its compiled model."""
    text = json.dumps({"env": config, "model": digest}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def action_layout(env: DexEnv) -> dict:
    emb = env.embodiment
    return {"actuators": list(emb.actuators), "low": emb.ctrl_range[:, 0].tolist(),
            "high": emb.ctrl_range[:, 1].tolist()}


def versions() -> dict:
    out = {name: importlib.metadata.version(name) for name in VERSIONED}
    out["python"] = platform.python_version()
    return out


def fps_of(env: DexEnv) -> int:
    """LeRobot's integer frame rate: one frame per control step."""
    fps = round(1.0 / env.control_dt)
    if abs(fps * env.control_dt - 1.0) > 1e-9:
        raise DatasetError(f"datasets need an integer control rate; sim.control_hz gives "
                           f"{1.0 / env.control_dt:g} Hz")
    return fps


def env_meta(env: DexEnv) -> dict:
    """Everything about the env a dataset records, its config hash included."""
    config, digest = env_config(env), model_digest(env.scene.model)
    layout = state_layout(env.scene.model, STATE_SPEC)
    return {
        "format": FORMAT,
        "task": env.task.name,
        "category": env.task.category,
        "embodiment": env.embodiment.name,
        "instruction": env.task.instruction,
        "env_config": config,
        "model_digest": digest,
        "config_hash": config_hash(config, digest),
        "versions": versions(),
        "action_layout": action_layout(env),
        "proprio_joints": list(env.embodiment.proprio_joints),
        "sim_state": {"spec": STATE_SPEC, "size": env.state_size,
                      "components": {k: [s.start, s.stop] for k, s in layout.items()}},
        "fps": fps_of(env),
        "episode_steps": env.episode_steps,
    }


def code_changes(meta: dict, env: DexEnv) -> list[str]:
    """What differs between a dataset's recorded env and `env`, rebuilt from its config."""
    now = env_meta(env)
    if now["config_hash"] == meta["config_hash"]:
        return []
    changes = []
    stored, current = meta["env_config"], now["env_config"]
    for section in sorted(set(stored) | set(current)):
        a, b = stored.get(section), current.get(section)
        if isinstance(a, dict) and isinstance(b, dict):
            changes += [f"{section}.{k}: {a.get(k, '(absent)')} -> {b.get(k, '(absent)')}"
                        for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
        elif a != b:
            changes.append(f"{section}: {a} -> {b}")
    if now["model_digest"] != meta["model_digest"]:
        changes.append("the compiled model differs (robot models, task objects or scene "
                       "code changed)")
    for key in ("action_layout", "sim_state", "proprio_joints"):
        if now[key] != meta[key]:
            changes.append(f"{key} changed")
    return changes or ["config hash differs"]


def read_meta(root: pathlib.Path) -> dict:
    """`meta/dexbench.json` of a dataset, or a DatasetError that says what to do."""
    path = root / META_FILE
    if not path.is_file():
        raise DatasetError(f"{root} is not a finished dexbench dataset ({META_FILE} is "
                           "missing); re-run the collect command that made it to finish it")
    try:
        meta = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise DatasetError(f"{path} is corrupt ({err}); re-create the dataset") from None
    if meta.get("format") != FORMAT:
        raise DatasetError(f"{path} has format {meta.get('format')!r}; this dexbench reads "
                           f"{FORMAT!r}")
    missing = [k for k in REQUIRED if k not in meta]
    if missing:
        raise DatasetError(f"{path} lacks {missing}; re-create the dataset")
    return meta


def damaged_files(root: pathlib.Path, meta: dict) -> list[str]:
    """One line per file `meta["files"]` lists that is missing or not the bytes written
    (damage that still parses included: parquet pages carry no checksums)."""
    problems = []
    for name, digest in meta["files"].items():
        path = root / name
        if not path.is_file():
            problems.append(f"{path} is missing; the dataset is incomplete")
        elif file_digest(path) != digest:
            problems.append(f"{path} differs from the checksum recorded when it was written: "
                            "it was changed or corrupted since; restore it or re-create the "
                            "dataset")
    return problems


def verify_files(root: pathlib.Path, meta: dict) -> None:
    """Refuse a dataset whose files changed since they were written, before any use."""
    problems = damaged_files(root, meta)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise DatasetError(f"{problems[0]}{more}; `python -m dexbench validate "
                           f"dataset={root}` lists every problem")
