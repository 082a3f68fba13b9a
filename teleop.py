"""Teleoperation: `python teleop.py task=PickCube embodiment=fr3_leap source=file:<keypoints>`
(a Hydra main; see dexbench/cli/teleop.py)."""

from dexbench.cli.teleop import hydra_entry

if __name__ == "__main__":
    hydra_entry()
