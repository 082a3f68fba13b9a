"""LeRobot env plugin: `lerobot-eval --env.type=dexbench --env.task=<Task> ...`.

LeRobot's scripts import every installed distribution named `lerobot_env_*`; importing
this one registers `DexbenchEnv` as the env type `dexbench`. dexbench itself is imported
only when a `dexbench` env is configured, so other LeRobot commands stay quick.
"""

from lerobot_env_dexbench.config import DexbenchEnv

__all__ = ["DexbenchEnv"]
