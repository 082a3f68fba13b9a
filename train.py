"""Training: `python train.py policy=dp task=PickCube`
(a Hydra main; see dexbench/cli/train.py)."""

from dexbench.cli.train import hydra_entry

if __name__ == "__main__":
    hydra_entry()
