"""Benchmarks: `python bench.py sim num_envs=64` (see dexbench/cli/bench.py)."""

from dexbench.cli.bench import entry

if __name__ == "__main__":
    entry()
