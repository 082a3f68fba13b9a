"""Reinforcement learning: `python rl.py task=PickCube num_envs=4096` (see dexbench/cli/rl.py)."""

from dexbench.cli.errors import run_cli
from dexbench.cli.rl import main

if __name__ == "__main__":
    run_cli(main)
