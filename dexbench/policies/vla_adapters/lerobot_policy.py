"""`policy=lerobot`: any LeRobot `PreTrainedPolicy` (ACT, diffusion, pi0, SmolVLA, ...)
run in-process on the batched env, with its own pre- and post-processors.

`policy.path` is a pretrained-model folder (what `lerobot-train` writes under
`<output_dir>/checkpoints/last/pretrained_model`) or a Hugging Face Hub id. The policy's
input features name dexbench observation groups by their dataset names
(`dexbench.data.features`: `observation.state` is proprio, `observation.images.<camera>`
a camera's RGB, ...), so the env is built with exactly the groups and cameras it takes;
`policy.rename_map` renames our keys to the policy's, as `lerobot-eval --rename_map` does.

LeRobot's `select_action` keeps one action queue (and observation history) for the whole
batch, while our evaluator resets each env when its episode ends. So, as LeRobot's own
policy server does, this adapter asks `predict_action_chunk` for the envs whose queue ran
dry, post-processes each action, and plays the first `replan_steps` (default: the
policy's `n_action_steps`); it keeps each env's last `n_obs_steps` observations itself,
the first one repeated after a reset as LeRobot does.
"""

from __future__ import annotations

import pathlib
from collections import deque
from collections.abc import Mapping
from typing import Any

import torch
import torch.nn.functional as F
from lerobot.configs import FeatureType
from lerobot.configs.policies import PreTrainedConfig
from lerobot.policies.factory import get_policy_class, make_pre_post_processors
from lerobot.utils.constants import ACTION

from dexbench.data.features import GROUP_OF, feature_key
from dexbench.embodiments.hands import SIDES
from dexbench.envs.camera_obs import THIRD_PERSON
from dexbench.envs.dex_env import DexEnv
from dexbench.policies.common.protocol import ActionLayoutError, PolicySpec

SETTINGS = ("path", "rename_map", "replan_steps", "prompt")
CONFIG_FILE = "config.json"
# Policies that predict only from the queues their own `select_action` fills.
QUEUE_ONLY = frozenset({"tdmpc", "vqbet", "multi_task_dit"})
CAMERAS = (*THIRD_PERSON, *(f"{side}/hand/wrist_cam" for side in SIDES))
IMAGE_GROUPS = {feature_key(f"rgb/{camera}"): f"rgb/{camera}" for camera in CAMERAS}


def settings(checkpoint: str | None, options: Mapping[str, Any]) -> dict[str, Any]:
    """`options` checked against this kind's settings (conf/policy/lerobot.yaml)."""
    if checkpoint is not None:
        raise ValueError("policy=lerobot loads policy.path=<pretrained_model folder or Hub "
                         "id>, not checkpoint=; drop checkpoint=")
    unknown = sorted(set(options) - set(SETTINGS))
    missing = [k for k in SETTINGS if k not in options]
    if unknown or missing:
        raise ValueError(f"policy=lerobot settings: unknown {unknown}, missing {missing}; it "
                         f"takes {', '.join(SETTINGS)} (conf/policy/lerobot.yaml)")
    s = dict(options)
    if not s["path"]:
        raise ValueError("policy=lerobot needs policy.path=<folder>: a pretrained_model "
                         "folder (lerobot-train writes <output_dir>/checkpoints/last/"
                         "pretrained_model) or a Hugging Face Hub id")
    if s["replan_steps"] is not None and int(s["replan_steps"]) < 1:
        raise ValueError(f"policy.replan_steps must be >= 1 or null, got {s['replan_steps']}")
    return {**s, "path": str(s["path"]), "rename_map": dict(s["rename_map"] or {})}


def load_config(path: str) -> PreTrainedConfig:
    """The policy's config, or one clear error saying what `path` should be."""
    folder = pathlib.Path(path)
    hub_id = path.count("/") == 1 and not path.startswith((".", "~"))
    if not folder.exists() and not hub_id:
        raise ValueError(f"policy.path={path} does not exist; give a pretrained_model folder "
                         "or a Hugging Face Hub id (<owner>/<name>)")
    if folder.exists() and not (folder / CONFIG_FILE).is_file():
        raise ValueError(f"policy.path={path} holds no {CONFIG_FILE}; give the "
                         "pretrained_model folder (lerobot-train writes <output_dir>/"
                         "checkpoints/last/pretrained_model)")
    try:
        config = PreTrainedConfig.from_pretrained(path)
    except Exception as err:  # the Hub client raises many kinds; all mean "cannot load"
        raise ValueError(f"policy.path={path} is neither a pretrained_model folder nor a "
                         f"Hub model that could be fetched ({type(err).__name__}: {err})"
                         ) from None
    if config.type in QUEUE_ONLY:
        raise ValueError(f"a {config.type} policy predicts only from its own select_action "
                         "queues, one for the whole batch; evaluate it with lerobot-eval "
                         "--env.type=dexbench")
    if getattr(config, "temporal_ensemble_coeff", None) is not None:
        raise ValueError("ACT's temporal ensembling keeps one ensemble for the whole batch; "
                         "evaluate it with lerobot-eval --env.type=dexbench")
    return config


def input_groups(config: PreTrainedConfig, rename_map: Mapping[str, str]) -> dict[str, str]:
    """The dexbench group behind each of the policy's input features."""
    ours = {policy_key: our_key for our_key, policy_key in rename_map.items()}
    groups = {}
    for key in config.input_features:
        name = ours.get(key, key)
        group = IMAGE_GROUPS.get(name) or GROUP_OF.get(name)
        if group is None:
            known = sorted({*GROUP_OF, *IMAGE_GROUPS})
            raise ValueError(f"the policy takes {key!r}, which no dexbench observation gives "
                             f"(they are {', '.join(known)}); map one to it with "
                             f"policy.rename_map='{{<ours>: {key}}}'")
        groups[key] = group
    return groups


def _spec(groups: dict[str, str]) -> PolicySpec:
    """The observation groups and cameras that give a policy's inputs."""
    cameras = tuple(g.removeprefix("rgb/") for g in groups.values() if g.startswith("rgb/"))
    obs = tuple(dict.fromkeys(g.partition("/")[0] for g in groups.values()))
    return PolicySpec(obs=obs, cameras=cameras or None)


def spec(checkpoint: str | None, options: Mapping[str, Any]) -> PolicySpec:
    s = settings(checkpoint, options)
    return _spec(input_groups(load_config(s["path"]), s["rename_map"]))


class LeRobotPolicy:
    """A LeRobot policy over a batched `DexEnv`, with one action queue and one
    observation history per env."""

    def __init__(self, env: DexEnv, policy: torch.nn.Module, preprocessor, postprocessor,
                 s: Mapping[str, Any]) -> None:
        config = policy.config
        self.policy, self._pre, self._post = policy, preprocessor, postprocessor
        self._groups = input_groups(config, s["rename_map"])
        self._ours = {policy_key: our_key for our_key, policy_key in s["rename_map"].items()}
        self._shapes = {k: tuple(ft.shape) for k, ft in config.input_features.items()
                        if ft.type is FeatureType.VISUAL}
        self._prompt = str(s["prompt"] or env.task.instruction)
        self._n_obs = int(config.n_obs_steps)
        # Actions played per chunk (None: all of it, for a policy without n_action_steps).
        self._replan = s["replan_steps"] or getattr(config, "n_action_steps", None)
        self.spec = _spec(self._groups)
        self.queries = 0  # policy inferences so far (each for the envs whose queue ran dry)
        self._queues: list[deque[torch.Tensor]] = [deque() for _ in range(env.num_envs)]
        self._history: dict[str, torch.Tensor] = {}
        self._fresh = torch.ones(env.num_envs, dtype=torch.bool)

    def reset(self, env_ids: torch.Tensor) -> None:
        for i in env_ids.tolist():
            self._queues[i].clear()
        self._fresh[env_ids.cpu()] = True

    def _frame(self, obs: dict[str, torch.Tensor],
               index: torch.Tensor | None = None) -> dict[str, torch.Tensor]:
        """The inputs of envs `index` (all: None) under our keys, as LeRobot's env
        preprocessing makes them: float32, images channel-first in [0, 1] at the size the
        policy takes."""
        frame = {}
        for key, group in self._groups.items():
            value = obs[group] if index is None else obs[group][index]
            if group.startswith("rgb/"):
                value = value.permute(0, 3, 1, 2).float() / 255
                size = self._shapes[key][1:]
                if tuple(value.shape[2:]) != size:
                    value = F.interpolate(value, size=size, mode="bilinear", antialias=True)
            frame[self._ours.get(key, key)] = value.float()
        return frame

    def _remember(self, frame: dict[str, torch.Tensor]) -> None:
        """Append every env's frame to its last `n_obs_steps` (filled with it after a
        reset)."""
        for key, value in frame.items():
            fresh = self._fresh.to(value.device).view(-1, *[1] * value.dim())
            stacked = value[:, None].expand(-1, self._n_obs, *value.shape[1:])
            if key in self._history:
                rolled = torch.cat([self._history[key][:, 1:], value[:, None]], dim=1)
                stacked = torch.where(fresh, stacked, rolled)
            self._history[key] = stacked.contiguous()
        self._fresh[:] = False

    @torch.no_grad()
    def _chunks(self, batch: dict[str, Any]) -> torch.Tensor:
        """(envs, steps, action_dim) actions of the policy, post-processed step by step."""
        chunk = self.policy.predict_action_chunk(self._pre(batch))
        if chunk.dim() == 2:
            chunk = chunk[:, None]
        steps = chunk[:, :self._replan]
        return torch.stack([self._post(steps[:, t]).cpu() for t in range(steps.shape[1])], 1)

    def act(self, obs: dict[str, torch.Tensor]) -> torch.Tensor:
        device = next(iter(obs.values())).device
        if self._n_obs > 1:  # the history takes every step's observation
            self._remember(self._frame(obs))
        empty = [i for i, q in enumerate(self._queues) if not q]
        if empty:
            index = torch.as_tensor(empty, device=device)
            inputs = ({k: v[index] for k, v in self._history.items()} if self._n_obs > 1
                      else self._frame(obs, index))
            chunks = self._chunks({**inputs, "task": [self._prompt] * len(empty)})
            for i, chunk in zip(empty, chunks, strict=True):
                self._queues[i].extend(chunk)
            self.queries += 1
        return torch.stack([q.popleft() for q in self._queues]).to(device)


def build(checkpoint: str | None, env: DexEnv, device: torch.device | str,
          options: Mapping[str, Any]) -> LeRobotPolicy:
    s = settings(checkpoint, options)
    config = load_config(s["path"])
    actions = config.output_features.get(ACTION)
    if actions is None or tuple(actions.shape) != (env.action_dim,):
        got = None if actions is None else tuple(actions.shape)
        raise ActionLayoutError(
            f"the policy outputs actions of shape {got}, but {env.embodiment.name} takes "
            f"({env.action_dim},) joint targets; evaluate it with the embodiment it was "
            "trained on (embodiment=<name>)")
    config.device = str(device)
    policy = get_policy_class(config.type).from_pretrained(s["path"], config=config)
    policy.eval()
    preprocessor, postprocessor = make_pre_post_processors(
        config, pretrained_path=s["path"], preprocessor_overrides={
            "device_processor": {"device": str(device)},
            "rename_observations_processor": {"rename_map": s["rename_map"]}})
    return LeRobotPolicy(env, policy, preprocessor, postprocessor, s)

