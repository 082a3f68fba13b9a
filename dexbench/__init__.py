"""dexbench: a dexterous-manipulation benchmark harness on MuJoCo."""

from dexbench.tasks.registry import make_env, register_gym_envs

register_gym_envs()

__all__ = ["make_env"]
