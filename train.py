"""Training: `python train.py policy=dp task=PickCube` (see dexbench/cli/train.py)."""

from dexbench.cli.errors import run_cli
from dexbench.cli.train import main

if __name__ == "__main__":
    run_cli(main)
