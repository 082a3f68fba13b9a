"""The mujoco_warp backend against the CPU backend, on warp's CPU device without a GPU.

The first run compiles mujoco_warp's kernels for the scene (minutes on a small CPU;
warp caches them under ~/.cache/warp, so later runs take seconds). One environment per
task is built and reused by every test.
"""

import functools

import numpy as np
import pytest
import torch

from dexbench.sim.warp import WarpBackend, capacity
from dexbench.tasks.registry import make_env

STEPS = 60  # 1 s of 60 Hz control
NUM_ENVS = 2


@functools.cache
def _env(task: str, backend: str):
    return make_env(task, num_envs=NUM_ENVS, seed=3, backend=backend, nthread=1)


def _reach_actions(env, target: torch.Tensor, stand_off: float, close: bool) -> list:
    """Open-loop actions: the palm moves to `stand_off` m before `target` (N, 3) at its
    height over 0.5 s, then (with `close`) the fingers close to the power grasp."""
    emb = env.embodiment
    home = torch.as_tensor(emb.poses["home"])
    power = torch.as_tensor(emb.poses["power"])
    axes = [emb.actuators.index(f"right/wrist/{c}") for c in "xyz"]
    palm_home = torch.tensor([-0.25, 0.0, 0.8], dtype=torch.float64)
    goal = target - palm_home - torch.tensor([stand_off, 0.0, 0.0], dtype=torch.float64)
    out = []
    for i in range(STEPS):
        reach = min(1.0, (i + 1) / (STEPS // 2))
        grasp = max(0.0, (i - STEPS // 2) / (STEPS // 2)) if close else 0.0
        a = (home + grasp * (power - home)).repeat(env.num_envs, 1)
        a[:, axes] = reach * goal
        out.append(a)
    return out


def _rollout(task: str, backend: str, target_obs: slice, stand_off: float, height: float,
             close: bool) -> tuple[np.ndarray, float]:
    env = _env(task, backend)
    keys = [[3, i, 0] for i in range(NUM_ENVS)]  # the same episodes whatever ran before
    obs = env.reset_to(torch.arange(NUM_ENVS), keys)
    target = obs["state"][:, target_obs].double().cpu()
    target[:, 2] += height
    qpos, contact = [], 0.0
    for action in _reach_actions(env, target, stand_off, close):
        obs, _, _, _, info = env.step(action)
        assert int(info["sim_warnings"].sum()) == 0
        contact = max(contact, float(obs["contact"].abs().max()))
        qpos.append(env.sim.field("qpos").double().cpu().numpy().copy())
    return np.stack(qpos), contact


@pytest.mark.parametrize("task,target_obs,stand_off,height,close", [
    ("PickCube", slice(0, 3), 0.07, 0.055, True),  # palm over the cube, fingers close on it
    ("OpenDrawer", slice(8, 11), 0.05, 0.0, False),  # palm pushes against the handle
])
def test_parity_with_cpu_backend_for_one_second(task, target_obs, stand_off, height, close):
    cpu, cpu_contact = _rollout(task, "cpu", target_obs, stand_off, height, close)
    gpu, gpu_contact = _rollout(task, "warp", target_obs, stand_off, height, close)
    model = _env(task, "cpu").scene.model
    diff = np.abs(cpu - gpu)
    for j in range(model.njnt):
        adr, kind = model.jnt_qposadr[j], model.jnt_type[j]
        if kind == 0:  # free joint: bound the object's position
            assert diff[:, :, adr:adr + 3].max() < 5e-3, model.joint(j).name
        else:
            bound = 5e-3 if kind == 2 else 0.05  # slide (m), hinge (rad)
            assert diff[:, :, adr].max() < bound, model.joint(j).name
    if task == "PickCube":  # the fingers did touch the cube on both backends
        assert cpu_contact > 0 and gpu_contact > 0


def test_fields_are_zero_copy_views_and_subset_reset_keeps_others():
    env = _env("PickCube", "warp")
    sim = env.sim
    assert isinstance(sim, WarpBackend)
    env.reset()
    for _ in range(3):
        env.step(env.home_action.repeat(NUM_ENVS, 1))
    qpos = sim.field("qpos")
    before = qpos.clone()
    sim.reset(torch.tensor([1]))
    assert torch.equal(qpos[0], before[0])  # the same tensor sees the reset in place
    np.testing.assert_allclose(qpos[1].cpu().numpy(), env.scene.model.qpos0, atol=1e-6)
    state = sim.get_state()
    sim.set_state(torch.tensor([1]), state[0:1])
    np.testing.assert_allclose(sim.get_state()[1].cpu().numpy(), state[0].cpu().numpy(),
                               atol=1e-6)


def test_per_world_model_field_changes_only_its_world():
    env = _env("PickCube", "warp")
    cube = env.scene.model.body("cube").id
    mass = env.sim.model_field("body_mass")
    assert mass.shape == (NUM_ENVS, env.scene.model.nbody)
    mass[1, cube] *= 3.0
    env.sim.set_const([1])
    subtree = env.sim.model_field("body_subtreemass")
    assert float(subtree[1, cube]) == pytest.approx(3 * float(subtree[0, cube]))


def test_capacity_overflow_is_counted_per_world():
    env = _env("PickCube", "cpu")
    assert capacity(env.scene.model)[0] >= 4
    sim = WarpBackend(env.scene.model, 1, nconmax=1, njmax=2)
    sim.reset(torch.tensor([0]))
    sim.forward(torch.tensor([0]))
    sim.step(1)  # the cube rests on the table: more contacts than one
    assert int(sim.warning_counts()[0]) >= 1
    sim.reset(torch.tensor([0]))
    assert int(sim.warning_counts()[0]) == 0


def test_a_diverged_world_is_reset_and_counted_as_on_the_cpu():
    """MuJoCo's auto-reset: a world whose state went non-finite or huge is put back to the
    model's defaults within the step (one warning); the other worlds go on untouched."""
    env = _env("PickCube", "warp")
    model, sim = env.scene.model, env.sim
    # 1e12 is beyond MuJoCo's mjMAXVAL; such a velocity also overflows mujoco_warp's
    # constraint rows for the step, which counts in every world: only NaN leaves world 0
    # without a warning.
    for bad, others_clean in ((float("nan"), True), (1e12, False)):
        env.reset()
        settled = sim.field("qpos").double().cpu().numpy().copy()
        sim.field("qvel")[1, 0] = bad
        sim.step(2)
        qpos = sim.field("qpos").double().cpu().numpy()
        assert int(sim.warning_counts()[1]) == 1
        assert np.isfinite(sim.field("xpos").cpu().numpy()).all()
        np.testing.assert_allclose(qpos[1], model.qpos0, atol=1e-6)
        np.testing.assert_allclose(qpos[0], settled[0], atol=0.01)  # world 0 stepped on
        if others_clean:
            assert int(sim.warning_counts()[0]) == 0


@pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU")
@pytest.mark.parametrize("camera", [False, True])
def test_gpu_step_never_waits_for_the_gpu_after_checking_actions(camera, monkeypatch):
    """The NaN check on the actions is a step's one host sync: everything after it (the
    physics graph, observation, reward and success terms, the ray-traced images) is only
    queued. A GPU stall queued right after the check must still be running when `step`
    returns; any host read of GPU data (torch's or warp's) would have waited it out."""
    groups = ["policy", "proprio", "contact", "state", "goal", "rgb", "depth"]
    extra = dict(obs=groups, cameras=["front"], image_size=(32, 32),
                 renderer="warp") if camera else {}
    env = make_env("PickCube", num_envs=4, backend="warp", **extra)
    env.reset()
    action = env.home_action.repeat(4, 1)
    env.step(action)  # captures the graphs
    torch.cuda.synchronize()
    stalled = torch.cuda.Event()
    check = env._validate

    def check_then_stall(actions):
        checked = check(actions)
        torch.cuda._sleep(2_000_000_000)  # a second or so of GPU clock cycles
        stalled.record()
        return checked

    monkeypatch.setattr(env, "_validate", check_then_stall)
    env.step(action)
    assert not stalled.query(), "step waited for the GPU after checking the actions"
    torch.cuda.synchronize()
