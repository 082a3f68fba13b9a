"""The LeRobot env plugin, through LeRobot's own plug-in discovery, env factory,
observation preprocessing, `lerobot-train` and `lerobot-eval`; and the same trained
policy in our evaluator (`eval.py policy=lerobot`)."""

import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from lerobot.envs.configs import EnvConfig
from lerobot.envs.factory import make_env, make_env_config
from lerobot.envs.utils import env_to_policy_features, preprocess_observation
from lerobot.utils.import_utils import register_third_party_plugins

from dexbench.cli import collect as collect_cli
from dexbench.cli import eval as eval_cli

BIN = pathlib.Path(sys.executable).parent  # the venv's console scripts
INSTRUCTION = "Pick up the cube and lift it above the table."
WRIST = "right/hand/wrist_cam"


@pytest.fixture(scope="module", autouse=True)
def _plugins():
    register_third_party_plugins()  # as every LeRobot script does first


def test_lerobot_finds_the_plugin_and_its_vector_env_speaks_lerobot():
    assert EnvConfig.get_choice_class("dexbench").__module__.startswith("lerobot_env_dexbench")
    cfg = make_env_config("dexbench", task="PickCube", obs_type="rgb",
                          cameras=f"front,{WRIST}", observation_width=32,
                          observation_height=24, shadows=False, episode_length=3,
                          render_width=40, render_height=30)
    features = env_to_policy_features(cfg)
    assert sorted(features) == ["action", "observation.images.front",
                                "observation.images.right_hand_wrist_cam",
                                "observation.prev_action", "observation.state"]
    assert features["observation.images.front"].shape == (3, 24, 32)

    vec = make_env(cfg, n_envs=2)["dexbench"][0]
    obs, _ = vec.reset(seed=[0, 1])
    assert obs["pixels"]["front"].dtype == np.uint8 and obs["pixels"]["front"].shape == (
        2, 24, 32, 3)
    batch = preprocess_observation(obs)
    assert {k: tuple(v.shape[1:]) for k, v in batch.items()} == {
        k: ft.shape for k, ft in features.items() if k != "action"}
    assert vec.call("task_description") == (INSTRUCTION, INSTRUCTION)
    assert vec.call("_max_episode_steps") == (3, 3)
    assert vec.envs[0].render().shape == (30, 40, 3)
    for _ in range(3):
        obs, _, terminated, truncated, info = vec.step(vec.action_space.sample())
    assert (terminated | truncated).all()
    assert info["final_info"]["is_success"].dtype == bool  # what lerobot-eval reads
    vec.close()

    with pytest.raises(ValueError, match="depth"):
        make_env_config("dexbench", obs_type="rgb_depth")


def _run(args: list[str], cwd: pathlib.Path) -> None:
    env = {**os.environ, "HF_HUB_OFFLINE": "1"}  # nothing is downloaded
    proc = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]


def test_lerobot_train_then_lerobot_eval_and_our_eval(tmp_path):
    data = tmp_path / "dataset"
    assert collect_cli.main(["task=PickCube", "num_demos=2", "num_envs=2",
                             "post_success_steps=2", f"out={data}", "progress=false",
                             "sim.nthread=1"]) == 0
    # The env declares the dataset's own feature names and shapes.
    stored = json.loads((data / "meta/info.json").read_text())["features"]
    for key, ft in env_to_policy_features(make_env_config("dexbench")).items():
        assert tuple(stored[key]["shape"]) == ft.shape, key

    _run([str(BIN / "lerobot-train"), "--dataset.repo_id=dexbench/PickCube",
          f"--dataset.root={data}", "--dataset.video_backend=pyav", "--policy.type=act",
          "--policy.device=cpu", "--policy.push_to_hub=false", "--policy.dim_model=16",
          "--policy.n_heads=2", "--policy.dim_feedforward=32", "--policy.n_encoder_layers=1",
          "--policy.n_decoder_layers=1", "--policy.n_vae_encoder_layers=1",
          "--policy.latent_dim=4", "--policy.chunk_size=4", "--policy.n_action_steps=4",
          "--steps=2", "--batch_size=2", "--num_workers=0", "--save_freq=2",
          f"--output_dir={tmp_path / 'train'}"], tmp_path)
    model = tmp_path / "train/checkpoints/last/pretrained_model"

    _run([str(BIN / "lerobot-eval"), f"--policy.path={model}", "--env.type=dexbench",
          "--env.task=PickCube", "--env.episode_length=4", "--env.render_width=32",
          "--env.render_height=32", "--eval.n_episodes=2", "--eval.batch_size=2",
          "--eval.use_async_envs=false", "--policy.device=cpu",
          f"--output_dir={tmp_path / 'lerobot_eval'}"], tmp_path)
    info = json.loads((tmp_path / "lerobot_eval/eval_info.json").read_text())
    assert info["overall"]["n_episodes"] == 2 and 0 <= info["overall"]["pc_success"] <= 100
    assert len(info["per_task"][0]["metrics"]["successes"]) == 2
    assert all(pathlib.Path(v).exists() for v in info["overall"]["video_paths"])

    assert eval_cli.main(["task=PickCube", "policy=lerobot", f"policy.path={model}",
                          "episodes=2", "num_envs=2", "horizon=4", "device=cpu",
                          "progress=false", "sim.nthread=1", "name=act"]) == 0
    run = next(pathlib.Path(os.environ["DEXBENCH_RUNS_DIR"]).glob("eval/PickCube/lerobot/act"))
    task = json.loads((run / "results.json").read_text())["tasks"][0]
    assert task["episodes"] == 2 and 0 <= task["success_rate"] <= 1
