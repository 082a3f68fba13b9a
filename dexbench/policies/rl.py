"""`policy=rl`: a policy trained by `python rl.py`, run deterministically: RSL-RL PPO's
actor mean, or a Stable-Baselines3 model (`rl.algo=sac|sb3_ppo`) with its normalizer.

The checkpoint is a training run folder (its newest `model_<it>.pt`) or one
`model_<it>.pt` in such a folder; `policy.json` beside it names the task, embodiment,
action layout, the observation groups the actor reads and how its outputs become joint
targets (`dexbench.rl.actions.ActionMap`).
"""

from __future__ import annotations

import json
import pathlib
import re
from collections.abc import Mapping
from typing import Any

import torch
from rsl_rl.models import MLPModel
from tensordict import TensorDict

from dexbench.envs.dex_env import DexEnv
from dexbench.policies.common.protocol import PolicySpec
from dexbench.rl.actions import ActionMap
from dexbench.rl.sb3_env import MODEL_FILE, load_sb3

META_FILE = "policy.json"


class CheckpointError(ValueError):
    """A checkpoint path that is not an RL training run or one of its models."""


def resolve(checkpoint: str | None) -> tuple[pathlib.Path, dict]:
    """The model file and the run's metadata for a run folder or model path."""
    if checkpoint is None:
        raise CheckpointError("policy=rl needs checkpoint=<runs/rl/... folder or model_<it>.pt>")
    path = pathlib.Path(checkpoint)
    run = path if path.is_dir() else path.parent
    meta_path = run / META_FILE
    if not meta_path.is_file():
        raise CheckpointError(f"{run} has no {META_FILE}: pass a folder written by rl.py "
                              "or a model_<it>.pt inside one")
    algo = json.loads(meta_path.read_text()).get("algo", "ppo")
    if algo != "ppo":  # Stable-Baselines3: one model.zip per run
        path = run / MODEL_FILE
        if not path.is_file():
            raise CheckpointError(f"{run} holds no {MODEL_FILE} yet")
    elif path.is_dir():
        models = sorted(run.glob("model_*.pt"),
                        key=lambda p: int(re.findall(r"\d+", p.stem)[-1]))
        if not models:
            raise CheckpointError(f"{run} holds no model_<it>.pt yet")
        path = models[-1]
    elif not path.is_file():
        raise CheckpointError(f"no such checkpoint {path}")
    return path, json.loads(meta_path.read_text())


def spec(checkpoint: str | None, options: Mapping[str, Any]) -> PolicySpec:
    _, meta = resolve(checkpoint)
    return PolicySpec(obs=tuple(meta["actor_groups"]), task=meta["task"],
                      embodiment=meta["embodiment"], action_layout=tuple(meta["actuators"]))


def load_actor(model_path: pathlib.Path, meta: dict, device: torch.device | str) -> MLPModel:
    """The trained actor network (with its observation normalizer), in eval mode."""
    net = meta["network"]
    dummy = TensorDict({"actor": torch.zeros(1, meta["actor_dim"])}, batch_size=[1])
    actor = MLPModel(dummy, {"actor": ["actor"]}, "actor", int(meta["action_dim"]),
                     hidden_dims=net["hidden_dims"], activation=net["activation"],
                     obs_normalization=net["obs_normalization"],
                     distribution_cfg={"class_name": "GaussianDistribution",
                                       "init_std": float(net["init_noise_std"])})
    state = torch.load(model_path, map_location="cpu", weights_only=False)
    actor.load_state_dict(state["actor_state_dict"])
    return actor.to(device).eval()


class RlPolicy:
    """Observation groups -> actor mean -> joint targets from the last targets."""

    def __init__(self, model_path: pathlib.Path, meta: dict, env: DexEnv,
                 device: torch.device | str) -> None:
        self.spec = PolicySpec(obs=tuple(meta["actor_groups"]), task=meta["task"],
                               embodiment=meta["embodiment"],
                               action_layout=tuple(meta["actuators"]))
        self._groups = tuple(meta["actor_groups"])
        self._map = ActionMap.from_meta(env, meta)
        self._device = device
        self._algo = meta.get("algo", "ppo")
        if self._algo == "ppo":
            self._actor = load_actor(model_path, meta, device)
        else:
            self._sb3, self._norm = load_sb3(model_path.parent, self._algo, device)

    def reset(self, env_ids: torch.Tensor) -> None:
        """Stateless: the last targets come back in the `policy` observation group."""

    @torch.no_grad()
    def act(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        x = torch.cat([obs[g].float() for g in self._groups], dim=1).to(self._device)
        if self._algo == "ppo":
            action = self._actor(TensorDict({"actor": x}, batch_size=[len(x)]))
        else:  # SB3's own normalization and deterministic prediction
            act, _ = self._sb3.predict(self._norm.normalize_obs(x.cpu().numpy()),
                                       deterministic=True)
            action = torch.as_tensor(act, dtype=torch.float32).clamp(-1.0, 1.0)
        return self._map.targets(obs["policy"].to(self._map.device), action)


def build(checkpoint: str | None, env: DexEnv, device: torch.device | str,
          options: Mapping[str, Any]) -> RlPolicy:
    model_path, meta = resolve(checkpoint)
    return RlPolicy(model_path, meta, env, device)
