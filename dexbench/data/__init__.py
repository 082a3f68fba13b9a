"""Demonstrations: recording, the dataset format (LeRobotDataset v3), replay, validation."""
