"""Reinforcement learning: `python rl.py task=PickCube num_envs=4096`
(a Hydra main; see dexbench/cli/rl.py)."""

from dexbench.cli.rl import hydra_entry

if __name__ == "__main__":
    hydra_entry()
