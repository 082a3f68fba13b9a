"""Closed-loop evaluation: `python eval.py +split=baseline19 policy=dp checkpoint=<path>`
(see dexbench/cli/eval.py)."""

from dexbench.cli.errors import run_cli
from dexbench.cli.eval import main

if __name__ == "__main__":
    run_cli(main)
