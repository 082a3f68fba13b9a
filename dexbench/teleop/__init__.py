"""Teleoperation: human hand keypoints retargeted to any embodiment's joint targets."""
