"""RSL-RL runner configuration from `conf/rl.yaml`'s `rl` section.

Defaults follow the DexVerse authors' PPO set-up: 8 steps per env and iteration, actor and
critic MLPs [1024, 1024, 512, 512] with ELU, initial noise std 1.0, clip 0.2, value
coefficient 1.0, no entropy bonus, 5 epochs x 4 minibatches, learning rate 1e-3 with the
adaptive schedule, gamma 0.98, lambda 0.95, gradient norm 1.0; but a desired KL of 0.01,
not 0.001, under which the learning rate shrank until nothing was learned (see
`docs/performance.md`). Observations are normalized by running statistics (their scales
differ by orders of magnitude).
"""

from __future__ import annotations

from omegaconf import DictConfig, OmegaConf


def runner_config(rl: DictConfig) -> dict:
    """The `train_cfg` dict `rsl_rl.runners.OnPolicyRunner` takes."""
    ppo = OmegaConf.to_container(rl.ppo, resolve=True)
    net = OmegaConf.to_container(rl.network, resolve=True)
    model = {"class_name": "MLPModel", "hidden_dims": net["hidden_dims"],
             "activation": net["activation"], "obs_normalization": net["obs_normalization"]}
    return {
        "num_steps_per_env": int(rl.num_steps_per_env),
        "save_interval": int(rl.save_interval),
        "obs_groups": {"actor": ["actor"], "critic": ["critic"]},
        "algorithm": {"class_name": "PPO", **ppo},
        "actor": {**model, "distribution_cfg": {"class_name": "GaussianDistribution",
                                                 "init_std": float(net["init_noise_std"])}},
        "critic": dict(model),
        "check_for_nan": True,
    }
