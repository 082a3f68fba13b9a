"""Reinforcement learning: RSL-RL PPO on batched `DexEnv`s (the warp backend on a GPU).

`vec_env.RslVecEnv` adapts a `DexEnv` to RSL-RL's `VecEnv` (actor and critic
observation sets, delta joint-target actions, time-outs), `rewards.RewardTerms` sums the
weighted reward terms a `conf/rl_rewards/` preset lists, and `config` turns
`conf/rl.yaml` into RSL-RL's runner configuration.
"""
