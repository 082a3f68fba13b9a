"""Closed-loop evaluation: `python eval.py +split=baseline19 policy=dp checkpoint=<path>`
(see dexbench/cli/eval.py); a Hydra main (`--help`, `-m`, `hydra/launcher=...`)."""

from dexbench.cli.eval import hydra_entry

if __name__ == "__main__":
    hydra_entry()
