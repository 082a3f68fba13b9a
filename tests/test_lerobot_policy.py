"""`policy=lerobot`: LeRobot policies (built and saved by LeRobot itself, never trained,
no downloaded weights) run in our batched evaluator act exactly as LeRobot's own
`select_action` loop over `preprocess_observation` does, keep one queue and history per
env, and refuse what cannot work with one clear message."""

import pathlib

import pytest
import torch
from lerobot.configs import FeatureType, PolicyFeature
from lerobot.envs.utils import preprocess_observation
from lerobot.policies.act.configuration_act import ACTConfig
from lerobot.policies.act.modeling_act import ACTPolicy
from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
from lerobot.policies.factory import make_pre_post_processors
from lerobot.policies.tdmpc.configuration_tdmpc import TDMPCConfig

from dexbench.policies.common.protocol import ActionLayoutError
from dexbench.policies.registry import policy_module
from dexbench.tasks.registry import make_env

lerobot_policy = policy_module("lerobot")
STATE_GROUPS = {"proprio": "observation.state", "state": "observation.environment_state",
                "contact": "observation.contact", "policy": "observation.prev_action"}
WRIST = "right/hand/wrist_cam"
WRIST_KEY = "observation.images.right_hand_wrist_cam"  # how datasets name its images
IMAGE = (24, 32)  # (height, width)


def _options(path, **overrides) -> dict:
    return {"path": path and str(path), "rename_map": {}, "replan_steps": None, "prompt": None,
            **overrides}


def _feature(key: str, shape: tuple[int, ...]) -> PolicyFeature:
    kind = (FeatureType.VISUAL if "images" in key else
            FeatureType.ENV if key.endswith("environment_state") else FeatureType.STATE)
    return PolicyFeature(type=kind, shape=shape)


def _save(policy_cls, config, folder: pathlib.Path) -> pathlib.Path:
    """A pretrained_model folder as lerobot-train writes it (untrained weights)."""
    stats = {}
    for key, ft in {**config.input_features, **config.output_features}.items():
        one = torch.ones(ft.shape[0]).view(-1, *[1] * (len(ft.shape) - 1))  # per channel
        stats[key] = {"mean": 0 * one, "std": one, "min": -one, "max": one}
    torch.manual_seed(0)
    policy = policy_cls(config)
    preprocessor, postprocessor = make_pre_post_processors(config, dataset_stats=stats)
    for part in (policy, preprocessor, postprocessor):
        part.save_pretrained(folder)
    return folder


def _lerobot_batch(obs: dict[str, torch.Tensor], cameras: tuple[str, ...] = ()) -> dict:
    """What lerobot-eval hands the preprocessor: LeRobot's own `preprocess_observation` of
    the env's observations in LeRobot's env conventions."""
    raw = {"agent_pos": obs["proprio"].numpy()}
    for group, key in STATE_GROUPS.items():
        if group != "proprio" and group in obs:
            raw[key.removeprefix("observation.")] = obs[group].numpy()
    if cameras:
        raw["pixels"] = {c.replace("/", "_"): obs[f"rgb/{c}"].numpy() for c in cameras}
    batch = preprocess_observation(raw)
    n = len(obs["proprio"])
    return {**batch, "task": ["Pick up the cube and lift it above the table."] * n}


@pytest.fixture(scope="module")
def act_folder(tmp_path_factory) -> pathlib.Path:
    """ACT on every state group and the wrist camera's images."""
    env = make_env("PickCube", num_envs=1, obs=list(STATE_GROUPS))
    shapes = env.obs_shapes()
    config = ACTConfig(
        input_features={**{key: _feature(key, shapes[g]) for g, key in STATE_GROUPS.items()},
                         WRIST_KEY: _feature(WRIST_KEY, (3, *IMAGE))},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (env.action_dim,))},
        device="cpu", dim_model=16, n_heads=2, dim_feedforward=32, n_encoder_layers=1,
        n_decoder_layers=1, n_vae_encoder_layers=1, latent_dim=4, chunk_size=4,
        n_action_steps=3, pretrained_backbone_weights=None, push_to_hub=False)
    return _save(ACTPolicy, config, tmp_path_factory.mktemp("act"))


def _reference(policy_cls, folder: pathlib.Path):
    policy = policy_cls.from_pretrained(folder)
    pre, post = make_pre_post_processors(policy.config, pretrained_path=str(folder))
    return policy, pre, post


def test_act_acts_as_select_action_with_one_queue_per_env(act_folder):
    spec = lerobot_policy.spec(None, _options(act_folder))
    assert set(spec.obs) == {*STATE_GROUPS, "rgb"} and spec.cameras == (WRIST,)
    env = make_env("PickCube", num_envs=2, obs=list(spec.obs), cameras=list(spec.cameras),
                   image_size=IMAGE[::-1], shadows=False)
    ours = lerobot_policy.build(None, env, "cpu", _options(act_folder))
    ref, pre, post = _reference(ACTPolicy, act_folder)
    obs = env.reset()
    for _ in range(4):
        action = ours.act(obs)
        with torch.no_grad():
            expected = post(ref.select_action(pre(_lerobot_batch(obs, spec.cameras))))
        torch.testing.assert_close(action, expected.to(action.dtype))
        obs = env.step(action)[0]
    assert ours.queries == 2  # chunks of n_action_steps=3 at steps 0 and 3

    # Env 1 alone starts over: it gets a fresh chunk, env 0 plays on from its queue.
    ours.reset(torch.tensor([1]))
    action = ours.act(obs)
    with torch.no_grad():
        batch = pre(_lerobot_batch(obs, spec.cameras))
        queued = post(ref.select_action(batch))
        fresh = post(ref.predict_action_chunk(batch)[:, 0])
    torch.testing.assert_close(action[0], queued[0].to(action.dtype))
    torch.testing.assert_close(action[1], fresh[1].to(action.dtype))
    assert ours.queries == 3

    # Camera images of another size are resized to the size the policy takes.
    big = make_env("PickCube", num_envs=1, obs=list(spec.obs), cameras=list(spec.cameras),
                   image_size=(48, 40), shadows=False)
    action = lerobot_policy.build(None, big, "cpu", _options(act_folder)).act(big.reset())
    assert action.shape == (1, env.action_dim) and torch.isfinite(action).all()


def test_diffusion_history_acts_as_select_action(tmp_path):
    keys = {g: STATE_GROUPS[g] for g in ("proprio", "state")}
    env = make_env("PickCube", num_envs=2, obs=list(keys))
    shapes = env.obs_shapes()
    config = DiffusionConfig(
        input_features={key: _feature(key, shapes[g]) for g, key in keys.items()},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (env.action_dim,))},
        device="cpu", n_obs_steps=2, horizon=8, n_action_steps=3, down_dims=(8, 16),
        kernel_size=3, n_groups=2, diffusion_step_embed_dim=8, num_inference_steps=2,
        push_to_hub=False)
    folder = _save(DiffusionPolicy, config, tmp_path / "diffusion")
    ours = lerobot_policy.build(None, env, "cpu", _options(folder))
    torch.manual_seed(1)
    observations, actions = [env.reset()], []
    for step in range(7):
        if step == 5:  # env 1 starts over: its history restarts from its current frame
            ours.reset(torch.tensor([1]))
        actions.append(ours.act(observations[-1]))
        observations.append(env.step(actions[-1])[0])
    assert ours.queries == 4  # both envs at steps 0 and 3, env 1 at step 5, env 0 at 6

    ref, pre, post = _reference(DiffusionPolicy, folder)
    solo, _, _ = _reference(DiffusionPolicy, folder)  # env 1 after its restart

    def lerobot(policy, obs, envs=slice(None)):
        with torch.no_grad():
            return post(policy.select_action(pre(_lerobot_batch(
                {k: v[envs] for k, v in obs.items()})))).to(actions[0].dtype)

    torch.manual_seed(1)  # the same noise: both draw it only for the same chunk queries
    for obs, action in zip(observations[:5], actions[:5], strict=True):
        torch.testing.assert_close(action, lerobot(ref, obs))
    torch.testing.assert_close(actions[5][0], lerobot(ref, observations[5])[0])  # queued
    torch.testing.assert_close(actions[5][1], lerobot(solo, observations[5], [1])[0])
    torch.testing.assert_close(actions[6][1], lerobot(solo, observations[6], [1])[0])


def _config_only(config, folder: pathlib.Path) -> str:
    config.save_pretrained(folder)
    return str(folder)


def test_settings_paths_and_features_give_one_clear_error(tmp_path, act_folder):
    with pytest.raises(ValueError, match=r"needs policy.path="):
        lerobot_policy.spec(None, _options(None))
    with pytest.raises(ValueError, match=r"not checkpoint="):
        lerobot_policy.spec("model.pt", _options(act_folder))
    with pytest.raises(ValueError, match=r"unknown \['steps'\]"):
        lerobot_policy.spec(None, {**_options(act_folder), "steps": 3})
    with pytest.raises(ValueError, match=r"holds no config.json; give the pretrained_model"):
        lerobot_policy.spec(None, _options(act_folder.parent))
    with pytest.raises(ValueError, match=r"does not exist"):  # a path, not a Hub id
        lerobot_policy.spec(None, _options(tmp_path / "outputs/train/pretrained_model"))

    single = ACTConfig(
        input_features={"observation.image": _feature("images", (3, *IMAGE)),
                        "observation.state": _feature("observation.state", (30,))},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (26,))},
        pretrained_backbone_weights=None, push_to_hub=False)
    path = _config_only(single, tmp_path / "single")
    with pytest.raises(ValueError, match=r"'observation.image'.*policy.rename_map"):
        lerobot_policy.spec(None, _options(path))
    renamed = lerobot_policy.spec(None, _options(
        path, rename_map={"observation.images.left": "observation.image"}))
    assert set(renamed.obs) == {"rgb", "proprio"} and renamed.cameras == ("left",)

    tdmpc = TDMPCConfig(
        input_features={"observation.state": _feature("observation.state", (30,))},
        output_features={"action": PolicyFeature(FeatureType.ACTION, (26,))},
        push_to_hub=False)
    with pytest.raises(ValueError, match=r"tdmpc policy .* lerobot-eval --env.type=dexbench"):
        lerobot_policy.spec(None, _options(_config_only(tdmpc, tmp_path / "tdmpc")))

    allegro = make_env("PickCube", "floating_allegro", num_envs=1, obs=list(STATE_GROUPS))
    with pytest.raises(ActionLayoutError, match=r"shape \(26,\).*embodiment=<name>"):
        lerobot_policy.build(None, allegro, "cpu", _options(act_folder))
