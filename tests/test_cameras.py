"""Camera observation groups: presets, determinism, point-cloud geometry, FPS."""

import mujoco
import numpy as np
import pytest
import torch
from test_tasks import TASK_KINDS

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.camera_obs import CROP_LO
from dexbench.envs.observations import PRESETS
from dexbench.envs.pointcloud import crop_mask, depth_to_world, farthest_point_sample, thin_evenly
from dexbench.tasks.registry import TASKS, make_env

SMALL = {"image_size": (32, 24), "num_points": 64}


def _expected_keys(preset: str, env) -> dict:
    p = PRESETS[preset]
    cams = ("front", "left", "right") if p.multiview else ("front",)
    shapes = {}
    for g in p.groups:
        if g == "rgb":
            shapes.update({f"rgb/{c}": ((24, 32, 3), torch.uint8) for c in cams})
        elif g == "depth":
            shapes.update({f"depth/{c}": ((24, 32), torch.float32) for c in cams})
        elif g == "pointcloud":
            shapes["pointcloud"] = ((64, 3), torch.float32)
        elif g == "policy":
            shapes["policy"] = ((env.action_dim,), torch.float32)
        elif g == "proprio":
            shapes["proprio"] = ((len(env.embodiment.proprio_joints),), torch.float32)
    return shapes


def _check_shapes(task: str, preset: str) -> None:
    env = make_env(task, "bimanual_floating_shadow" if TASKS[task].bimanual
                   else "floating_shadow", num_envs=2, obs=preset, **SMALL)
    obs = env.reset()
    expected = _expected_keys(preset, env)
    for key, (shape, dtype) in expected.items():
        hist = (PRESETS[preset].history,) if PRESETS[preset].history else ()
        assert tuple(obs[key].shape) == (2, *hist, *shape), (task, preset, key)
        assert obs[key].dtype == dtype
    assert "privileged" not in obs
    extra = set(obs) - set(expected) - {"contact", "state", "goal"}
    assert not extra, extra


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("task", ["PickCube", "BimanualLiftTray"])
def test_every_preset_has_documented_shapes(task, preset):
    _check_shapes(task, preset)


# Per task, the presets whose observations depend on the task's scene: its state, contact
# and goal vectors, and the point cloud cropped to its workspace from three views (the
# images' shapes are the preset's alone, checked above).
@pytest.mark.parametrize("preset", ["state", "3view_pointcloud"])
@pytest.mark.parametrize("task", TASK_KINDS)
def test_every_task_has_the_documented_shapes(task, preset):
    _check_shapes(task, preset)


def test_same_seed_same_images_and_envs_differ():
    a = make_env("PickCube", num_envs=2, seed=4, obs="rgb_depth", image_size=(48, 48))
    b = make_env("PickCube", num_envs=2, seed=4, obs="rgb_depth", image_size=(48, 48))
    oa, ob = a.reset(), b.reset()
    assert torch.equal(oa["rgb/front"], ob["rgb/front"])
    assert torch.equal(oa["depth/front"], ob["depth/front"])
    assert not torch.equal(oa["rgb/front"][0, -1], oa["rgb/front"][1, -1]), "cubes differ"


def test_wrist_cameras_render():
    env = make_env("BimanualLiftTray", num_envs=1, obs=["rgb"], image_size=(32, 32),
                   cameras=["right/hand/wrist_cam", "left/hand/wrist_cam"])
    obs = env.reset()
    assert obs["rgb/right/hand/wrist_cam"].shape == (1, 32, 32, 3)
    assert obs["rgb/left/hand/wrist_cam"].float().std() > 0


def _box_distance(p_local: np.ndarray, half: float) -> np.ndarray:
    """Unsigned distance of points (box frame) to the surface of a cube."""
    q = np.abs(p_local) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
    inside = np.minimum(q.max(axis=-1), 0.0)
    return np.abs(outside + inside)


def test_depth_points_of_the_cube_lie_on_its_surface():
    env = make_env("PickCube", num_envs=2, seed=1, obs=["depth"], image_size=(160, 160),
                   cameras=["front", "left"])
    env.reset()
    frames = env.cameras.renderer.render(["front", "left"], rgb=False, depth=True)
    pos = env.view.body_pos("cube").numpy()
    quat = env.view.body_quat("cube").numpy()
    checked = 0
    for cam, f in frames.items():
        pts = depth_to_world(f.depth, f.fovy, f.cam_pos, f.cam_mat)
        pts = pts.numpy()
        for e in range(2):
            # near the cube and above the table top (which the cube stands on)
            near = pts[e][(np.linalg.norm(pts[e] - pos[e], axis=1) < 0.05)
                          & (pts[e][:, 2] > TABLE_TOP_Z + 0.001)]
            rot = np.zeros(9)
            mujoco.mju_quat2Mat(rot, quat[e])
            local = (near - pos[e]) @ rot.reshape(3, 3)
            dist = _box_distance(local, 0.025)
            assert dist.max(initial=0.0) < 0.003, (cam, e, dist.max())
            checked += len(near)
    assert checked > 100


def test_pointcloud_is_cropped_to_the_table_volume():
    env = make_env("PickCube", num_envs=2, obs="pointcloud", image_size=(64, 64))
    cloud = env.reset()["pointcloud"][:, -1]
    assert cloud.shape == (2, 512, 3)
    assert crop_mask(cloud.double(), CROP_LO, (0.6, 0.75, 1.2)).all()
    assert (cloud[..., 2] >= CROP_LO[2] - 1e-6).all()


def test_a_bimanual_point_cloud_fuses_the_two_side_views():
    """The paper fuses two views for bimanual tasks: our side cameras, each facing one
    hand; one hand keeps the front view, and an explicit camera list still wins."""
    from dexbench.envs.camera_obs import BIMANUAL_CLOUD, default_cameras

    assert default_cameras(False, ("pointcloud",), arity=2) == BIMANUAL_CLOUD
    assert default_cameras(False, ("pointcloud",), arity=1) == ("front",)
    assert default_cameras(False, ("rgb",), arity=2) == ("front",)
    env = make_env("BimanualLiftTray", num_envs=1, obs="pointcloud", image_size=(32, 32))
    assert env.cameras.cloud_cameras == ("left", "right")
    env = make_env("BimanualLiftTray", num_envs=1, obs="pointcloud", image_size=(32, 32),
                   cameras=["front"])
    assert env.cameras.cloud_cameras == ("front",)


def _fps_reference(points: np.ndarray, valid: np.ndarray, n: int) -> list[int]:
    idx = [int(np.flatnonzero(valid)[0])]
    dist = np.full(len(points), np.inf)
    dist[~valid] = -1
    for _ in range(n - 1):
        d = ((points - points[idx[-1]]) ** 2).sum(axis=1)
        dist = np.where(valid, np.minimum(dist, d), dist)
        idx.append(int(dist.argmax()))
    return idx


def test_fps_matches_brute_force_reference():
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(3, 500, 3))
    valid = rng.uniform(size=(3, 500)) < 0.7
    got = farthest_point_sample(torch.from_numpy(pts), torch.from_numpy(valid), 32)
    for b in range(3):
        assert got[b].tolist() == _fps_reference(pts[b], valid[b], 32)


_FPS_CASES = "[(3, 37, 8), (2, 1024, 200), (2, 100, 150)]"
_FPS_KERNEL_CHECK = f"""
import torch
from dexbench.envs.fps_triton import farthest_point_sample_triton
from dexbench.envs.pointcloud import farthest_point_sample
g = torch.Generator().manual_seed(0)
for batch, count, n in {_FPS_CASES}:
    pts = torch.rand(batch, count, 3, generator=g)
    mask = torch.rand(batch, count, generator=g) > 0.3
    mask[0] = False
    mask[-1, :] = False
    mask[-1, 5] = mask[-1, 9] = True
    assert torch.equal(farthest_point_sample_triton(pts, mask, n),
                       farthest_point_sample(pts, mask, n)), (batch, count, n)
"""


def test_fps_kernel_follows_the_torch_loop_in_triton_interpreter():
    """The CUDA kernel's program, run by Triton's CPU interpreter, picks the torch loop's
    points exactly: empty clouds, two valid points repeated, 200 of 1024."""
    pytest.importorskip("triton")
    import os
    import subprocess
    import sys

    env = {**os.environ, "TRITON_INTERPRET": "1"}
    done = subprocess.run([sys.executable, "-c", _FPS_KERNEL_CHECK], env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs CUDA")
def test_fps_kernel_on_cuda_picks_the_torch_loops_points():
    g = torch.Generator().manual_seed(3)
    pts = torch.rand(8, 2048, 3, generator=g).cuda()
    mask = (torch.rand(8, 2048, generator=g) > 0.2).cuda()
    mask[1] = False
    fast = farthest_point_sample(pts, mask, 512)
    loop = farthest_point_sample(pts, mask, 512, kernel=False)
    assert (fast != loop).any(dim=1).sum() <= 1  # a last-bit near-tie at most


def test_thinning_keeps_every_point_that_fits_and_spaces_the_rest_evenly():
    """Clouds with no, few, exactly `keep` and many valid points, thinned at once."""
    rng = np.random.default_rng(1)
    mask = np.zeros((4, 300), dtype=bool)
    for row, count in zip(mask, (0, 7, 16, 211), strict=True):
        row[rng.choice(300, count, replace=False)] = True
    idx, ok = thin_evenly(torch.from_numpy(mask), 16)
    for row, got, fits in zip(mask, idx.numpy(), ok.numpy(), strict=True):
        valid = np.flatnonzero(row)
        want = valid if len(valid) <= 16 else valid[np.arange(16) * (len(valid) - 1) // 15]
        assert fits.sum() == len(want) and fits[:len(want)].all()
        assert got[:len(want)].tolist() == want.tolist()
        assert got.max() < 300


def _variation_env(**kw):
    from dexbench.envs.variation import PhysicalVariation, VisualVariation
    return make_env("PickCube", num_envs=3, seed=5, obs=["rgb", "proprio"],
                    image_size=(48, 48), visual=VisualVariation(enabled=True, **kw),
                    physical=PhysicalVariation(enabled=True, obs_noise=0.01))


def test_visual_variation_differs_across_envs_and_reproduces_with_seed():
    a, b = _variation_env().reset(), _variation_env().reset()
    assert torch.equal(a["rgb/front"], b["rgb/front"]) and torch.equal(a["proprio"],
                                                                      b["proprio"])
    imgs = a["rgb/front"].float()
    assert all((imgs[i] - imgs[j]).abs().mean() > 2.0 for i, j in ((0, 1), (1, 2), (0, 2)))
    test = _variation_env(split="test").reset()
    assert not torch.equal(test["rgb/front"], a["rgb/front"])


def test_variation_does_not_change_the_task_samples():
    plain = make_env("PickCube", num_envs=3, seed=5).reset()["state"]
    varied = _variation_env()
    varied.reset()
    torch.testing.assert_close(varied.task.state_obs(varied.view).float(), plain)


def test_physical_variation_scales_within_ranges():
    env = _variation_env()
    env.reset()
    model, mass = env.scene.model, env.sim.model_field("body_mass")
    cube = model.body("cube").id
    ratio = mass[:, cube] / model.body_mass[cube]
    assert ((ratio >= 0.7) & (ratio <= 1.3)).all() and len(set(ratio.tolist())) == 3


def test_varied_field_of_view_still_reconstructs_the_table_plane():
    from dexbench.envs.variation import VisualVariation
    env = make_env("PickCube", num_envs=3, obs=["depth"], image_size=(64, 64),
                   visual=VisualVariation(enabled=True, fov_jitter_deg=8.0))
    env.reset()
    f = env.cameras.renderer.render(["front"], rgb=False, depth=True)["front"]
    assert len(set(f.fovy.tolist())) == 3
    pts = depth_to_world(f.depth, f.fovy, f.cam_pos, f.cam_mat)
    z = pts[..., 2]
    table = (pts[..., 0].abs() < 0.2) & (pts[..., 1].abs() < 0.5) & (z > 0.55) & (z < 0.605)
    assert table.sum() > 100
    assert (pts[..., 2][table] - TABLE_TOP_Z).abs().max() < 0.003


@pytest.mark.parametrize("visual", ["fixed", "train"])
def test_warp_renderer_depth_agrees_with_cpu_renderer(visual):
    """Same cameras, same camera model: mujoco_warp's ray-traced depth (on warp's CPU
    device here) matches OpenGL's to < 5 mm median on pixels both see, also with
    per-world camera pose, field of view and materials varied."""
    from dexbench.envs.variation import VisualVariation
    from dexbench.sim.warp_render import WarpRenderer

    variation = VisualVariation(enabled=visual != "fixed", split="train")
    env = make_env("StackCube", num_envs=3, seed=2, obs="rgb_depth", image_size=(64, 48),
                   visual=variation)
    env.reset()
    cams = ["front", "left", "right", "right/hand/wrist_cam"]
    cpu = env.cameras.renderer.render(cams, rgb=True, depth=True)
    warp = WarpRenderer(env.sim, 64, 48, device="cpu").render(cams, rgb=True, depth=True)
    for cam in cams:
        a, b = cpu[cam], warp[cam]
        assert b.rgb.shape == a.rgb.shape and b.rgb.dtype == torch.uint8
        assert b.depth.shape == a.depth.shape and b.depth.dtype == torch.float32
        torch.testing.assert_close(b.cam_pos, a.cam_pos)
        torch.testing.assert_close(b.fovy, a.fovy)
        seen = (a.depth < 10) & (b.depth < 10)
        assert seen.float().mean() > 0.5, cam
        diff = (a.depth - b.depth).abs()[seen]
        assert diff.median() < 0.005, f"{cam}: median |depth diff| {diff.median():.4f} m"
        assert (b.rgb.float().mean() - a.rgb.float().mean()).abs() < 40, cam


@pytest.mark.parametrize("kind", ["cpu", "warp"])
def test_shadows_off_only_brightens_shaded_pixels(kind):
    """`shadows=False` (camera.shadows) removes the hand's and objects' shadows on both
    renderers: geometry (depth) is unchanged, pixels get brighter (but for a few at
    shadow-map edges), and many do."""
    from dexbench.sim.render import CpuRenderer
    from dexbench.sim.warp_render import WarpRenderer

    env = make_env("StackCube", num_envs=1, seed=2, obs="state")
    env.reset()

    def render(shadows: bool):
        if kind == "cpu":
            renderer = CpuRenderer(env.sim, 64, 48, shadows)
        else:
            renderer = WarpRenderer(env.sim, 64, 48, device="cpu", shadows=shadows)
        return renderer.render(["front"], rgb=True, depth=True)["front"]

    lit, shaded = render(False), render(True)
    torch.testing.assert_close(lit.depth, shaded.depth)
    gain = lit.rgb.float().mean(dim=-1) - shaded.rgb.float().mean(dim=-1)
    darker, brighter = int((gain < -3).sum()), int((gain > 10).sum())
    assert darker <= 0.002 * gain.numel(), f"{kind}: {darker} px darker without shadows"
    assert brighter > 100, f"{kind}: only {brighter} px lost a shadow"


def test_warp_point_clouds_agree_with_opengl_point_clouds():
    """The `pointcloud` group through the warp renderer (warp's CPU device here) describes
    the same surfaces as through OpenGL: every point of either cloud lies near the other
    cloud (the farthest-point samples differ, the geometry does not)."""
    clouds = {}
    for renderer in ("cpu", "warp"):
        env = make_env("StackCube", num_envs=2, seed=2, obs="pointcloud", image_size=(96, 72),
                       renderer=renderer)
        clouds[renderer] = env.reset()["pointcloud"][:, -1].float()
    a, b = clouds["cpu"], clouds["warp"]
    assert a.shape == b.shape and a.shape[1:] == (512, 3)
    gaps = torch.cat([torch.cdist(a, b).min(dim=2).values, torch.cdist(b, a).min(dim=2).values])
    assert gaps.median() < 0.005, f"median gap {gaps.median():.4f} m"
    assert torch.quantile(gaps, 0.95) < 0.02, f"95% gap {torch.quantile(gaps, 0.95):.4f} m"


def _first_cloud(**kwargs) -> torch.Tensor:
    env = make_env("StackCube", num_envs=2, seed=2, obs="pointcloud", image_size=(64, 48),
                   **kwargs)
    return env.reset()["pointcloud"][:, -1]


def test_point_cloud_device_cpu_is_the_cpu_renderers_default():
    assert torch.equal(_first_cloud(), _first_cloud(cloud_device="cpu"))


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs CUDA")
def test_point_cloud_on_cuda_agrees_with_the_cpu_and_comes_back_on_the_cpu():
    """Computed on the GPU, the cloud is returned where the renderer's images are and
    describes the same points (the sums may differ in the last bits, hence the sampling
    in rare ties)."""
    cpu, gpu = _first_cloud(), _first_cloud(cloud_device="cuda")
    assert gpu.device.type == "cpu" and gpu.shape == cpu.shape
    gaps = torch.cdist(gpu.double(), cpu.double(),
                       compute_mode="donot_use_mm_for_euclid_dist").min(dim=2).values
    assert torch.quantile(gaps, 0.95) < 1e-5
