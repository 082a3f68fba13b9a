"""Shared fixtures: outputs go to a temp dir, never into the checkout."""

import os

# Headless rendering, decided before any test module imports mujoco.
os.environ.setdefault("MUJOCO_GL", "egl")

import pytest


@pytest.fixture(autouse=True)
def _runs_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path / "runs"))
