"""`python -m dexbench cloud`: a .ply of an env's point-cloud observation or of a dataset
frame through Open3D (the optional `open3d` extra; its tests skip without it), and one
error line where Open3D or a display is missing."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from dexbench.cli.cloud import cloud
from dexbench.cli.config import ConfigError
from dexbench.policies.common.demos import Demos
from dexbench.tasks.registry import make_env

TINY = ["sim.nthread=1", "camera.width=64", "camera.height=64", "camera.num_points=64"]


def test_without_open3d_one_line_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "open3d", None)  # `import open3d` raises ImportError
    with pytest.raises(ConfigError, match=r"pip install -e '\.\[open3d\]'") as err:
        cloud(["task=PickCube", f"out={tmp_path / 'c.ply'}", *TINY])
    assert "\n" not in str(err.value) and not (tmp_path / "c.ply").exists()


def test_view_needs_a_desktop_and_out_a_ply(tmp_path, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(ConfigError, match="view=true needs a desktop"):
        cloud(["task=PickCube", "view=true", *TINY])
    with pytest.raises(ConfigError, match=r"must end in \.ply"):
        cloud(["task=PickCube", f"out={tmp_path / 'c.pcd'}", *TINY])
    with pytest.raises(ConfigError, match="pass out="):
        cloud(["task=PickCube", *TINY])


def test_env_cloud_after_reset_to_ply(tmp_path):
    o3d = pytest.importorskip("open3d")
    out = tmp_path / "clouds" / "pick.ply"
    assert cloud(["task=PickCube", "seed=3", f"out={out}", *TINY]) == 0
    env = make_env("PickCube", num_envs=1, seed=3, obs=["pointcloud"], nthread=1,
                   image_size=(64, 64), num_points=64)
    expected = env.reset()["pointcloud"][0].numpy()
    read = o3d.io.read_point_cloud(str(out))
    np.testing.assert_allclose(np.asarray(read.points), expected, atol=1e-6)
    assert np.asarray(read.colors).shape == (64, 3)


def test_dataset_frame_to_ply(tmp_path):
    o3d = pytest.importorskip("open3d")
    clouds = np.random.default_rng(0).uniform(-0.3, 0.3, (5, 64, 3)).astype(np.float32)
    demos = tmp_path / "demos.npz"
    Demos(meta={}, actions=np.zeros((5, 2), np.float32), obs={"pointcloud": clouds},
          episode_ends=np.array([2, 5]), source="test").save(demos)
    out = tmp_path / "frame.ply"
    assert cloud([f"dataset={demos}", "episode=1", "frame=2", f"out={out}"]) == 0
    read = np.asarray(o3d.io.read_point_cloud(str(out)).points)
    np.testing.assert_allclose(read, clouds[4].astype(np.float16), atol=1e-6)
    with pytest.raises(ConfigError, match=r"frame=3: episode 1 has frames 0\.\.2"):
        cloud([f"dataset={demos}", "episode=1", "frame=3", f"out={out}"])
