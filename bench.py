"""Benchmarks: `python bench.py sim num_envs=64` (see dexbench/cli/bench.py)."""

from dexbench.cli.bench import main
from dexbench.cli.errors import run_cli

if __name__ == "__main__":
    run_cli(main)
