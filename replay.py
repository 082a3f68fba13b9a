"""Replay: `python replay.py dataset=<folder> obs=rgb`
(a Hydra main; see dexbench/cli/replay.py)."""

from dexbench.cli.replay import hydra_entry

if __name__ == "__main__":
    hydra_entry()
