"""Demonstrations: `python collect.py task=PickCube num_demos=50` (see dexbench/cli/collect.py)."""

from dexbench.cli.collect import main
from dexbench.cli.errors import run_cli

if __name__ == "__main__":
    run_cli(main)
