"""Shared fixtures: outputs go to a temp dir, never into the checkout."""

# Importing dexbench first picks headless rendering (EGL where it exists) before any test
# module imports mujoco.
import pathlib

import pytest

import dexbench  # noqa: F401


@pytest.fixture(autouse=True)
def _runs_in_tmp(tmp_path, monkeypatch):
    monkeypatch.setenv("DEXBENCH_RUNS_DIR", str(tmp_path / "runs"))


@pytest.fixture(scope="session")
def pickcube_demos(tmp_path_factory) -> pathlib.Path:
    """Three PickCube demonstrations by the scripted expert, for the tests that train or
    start from demonstrations (read-only: a DP3 replay is written beside, not into, it)."""
    from dexbench.data.collect import CollectSettings, collect
    from dexbench.experts import make_expert
    from dexbench.tasks.registry import make_env

    env = make_env("PickCube", num_envs=3, seed=3, nthread=1)
    root = tmp_path_factory.mktemp("demos") / "PickCube"
    stats = collect(env, make_expert(env), root, CollectSettings(3, 9, post_success_steps=2),
                    {}, progress=False)
    assert stats["successes"] == 3
    return root

