"""Replay: `python replay.py dataset=<folder> obs=rgb` (see dexbench/cli/replay.py)."""

from dexbench.cli.errors import run_cli
from dexbench.cli.replay import main

if __name__ == "__main__":
    run_cli(main)
