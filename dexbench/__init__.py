"""dexbench: a dexterous-manipulation benchmark harness on MuJoCo."""

import ctypes.util
import os

# Headless rendering by default (set MUJOCO_GL=glfw for a desktop); must precede mujoco.
# Only where libEGL exists: mujoco fails to import with MUJOCO_GL=egl and no libEGL, and
# state-only and warp-rendered use needs no OpenGL at all.
if "MUJOCO_GL" not in os.environ and ctypes.util.find_library("EGL"):
    os.environ["MUJOCO_GL"] = "egl"

from dexbench.tasks.registry import make_env, register_gym_envs

register_gym_envs()

__all__ = ["make_env"]
