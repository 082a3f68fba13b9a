"""Shared fixtures: outputs go to a temp dir, never into the checkout."""

# Importing dexbench first picks headless rendering (EGL where it exists) before any test
# module imports mujoco.
import pytest

import dexbench  # noqa: F401


@pytest.fixture(autouse=True)
def _runs_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path / "runs"))
