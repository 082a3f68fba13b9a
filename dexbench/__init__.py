"""dexbench: a dexterous-manipulation benchmark harness on MuJoCo."""

import os

# Headless rendering by default (set MUJOCO_GL=glfw for a desktop); must precede mujoco.
os.environ.setdefault("MUJOCO_GL", "egl")

from dexbench.tasks.registry import make_env, register_gym_envs

register_gym_envs()

__all__ = ["make_env"]
