"""Demonstrations: `python collect.py task=PickCube num_demos=50`
(a Hydra main; see dexbench/cli/collect.py)."""

from dexbench.cli.collect import hydra_entry

if __name__ == "__main__":
    hydra_entry()
