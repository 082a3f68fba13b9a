"""BimanualHandover and the per-hand, per-link contact forces it is judged by.

`SceneView.link_forces` against MuJoCo's own contact forces; the paper's rule (the left
hand presses on the cube with at least 1.6 N on one link, the right hand not touching
it), one near miss per clause (a grip just under 1.6 N, the right hand still touching,
the cube falling); and the warp backend's forces against the CPU backend's.
"""

import functools

import mujoco
import numpy as np
import pytest
import torch
from test_tasks import _fresh, _set_joint, _set_pose

from dexbench.tasks.bimanual_handover import GRIP_FORCE, HALF
from dexbench.tasks.registry import make_env

CUBE_AT = np.array([0.0, 0.0, 0.85])  # in the air between the hands


def _settle(env) -> None:
    """Derived fields, contact forces included, for the state as written."""
    env.sim.forward(torch.arange(env.num_envs), acceleration=True)


def _hand_geom(env, side: str, link: str) -> int:
    """A collision geom of hand `side`'s body `<side>/hand/<link>`."""
    model = env.scene.model
    body = model.body(f"{side}/hand/{link}").id
    return next(g for g in env.scene.hand_geoms if model.geom_bodyid[g] == body)


def _gap(env, geom: int) -> float:
    """Signed distance (m) from hand geom `geom` to the cube, in env 0."""
    model, data = env.scene.model, env.sim.batch.get_data(0)
    cube = model.geom("cube/geom").id
    return mujoco.mj_geomDistance(model, data, geom, cube, 0.5, np.zeros(6))


def _press(env, side: str, link: str, depth: float, up: bool) -> None:
    """Move hand `side`'s wrist until `link` presses `depth` m into the top of the cube
    from straight above (`up`: into its bottom from below), 1.5 cm to the hand's own
    side of its middle (the hand is palm-down)."""
    geom = _hand_geom(env, side, link)
    qpos = env.sim.field("qpos")[0]
    adr = {a: env.scene.model.joint(f"{side}/wrist/{a}").qposadr[0] for a in "xyz"}
    sign = -1.0 if up else 1.0
    _settle(env)
    aside = 0.015 if side == "left" else -0.015
    start = CUBE_AT + [0.0, aside, sign * (HALF + 0.05)]
    move = start - env.sim.field("geom_xpos")[0, geom].numpy()
    for i, a in enumerate("xyz"):
        _set_joint(env, f"{side}/wrist/{a}", float(qpos[adr[a]]) + float(move[i]))
    _settle(env)
    _set_joint(env, f"{side}/wrist/z",
               float(qpos[adr["z"]]) - sign * (_gap(env, geom) + depth))
    _settle(env)


def _state(env, left: float | None, right: float | None = None) -> None:
    """The cube still in the air, the left index tip pressing `left` m into its top and
    the right one `right` m into its bottom (None: that hand at home)."""
    env.reset()
    _set_pose(env, "cube", CUBE_AT)
    if left is not None:
        _press(env, "left", "lh_ffdistal", left, up=False)
    if right is not None:
        _press(env, "right", "rh_ffdistal", right, up=True)
    _settle(env)


def _ok(env) -> bool:
    return bool(env.task.success(env.view)[0])


def _strongest(env, side: str) -> float:
    return float(env.view.link_forces("cube", side).norm(dim=-1).max())


def test_link_forces_are_mujocos_contact_forces_per_link():
    env = _fresh("BimanualHandover")
    _state(env, left=0.002)
    model, data = env.scene.model, env.sim.batch.get_data(0)
    cube = model.geom("cube/geom").id
    links = [model.body(b).name for b in sorted({model.geom_bodyid[g]
                                                 for g in env.scene.hand_geoms})
             if model.body(b).name.startswith("left/hand/")]
    expected = np.zeros((len(links), 3))
    for i in range(data.ncon):
        c = data.contact[i]
        other = c.geom2 if c.geom1 == cube else c.geom1 if c.geom2 == cube else None
        name = None if other is None else model.body(model.geom_bodyid[other]).name
        if name in links:
            local = np.zeros(6)
            mujoco.mj_contactForce(model, data, i, local)
            expected[links.index(name)] += c.frame.reshape(3, 3).T @ local[:3]
    sensed = env.view.link_forces("cube", "left")[0].numpy()
    assert sensed.shape == (len(links), 3)
    np.testing.assert_allclose(np.linalg.norm(sensed, axis=1),
                               np.linalg.norm(expected, axis=1), rtol=1e-6, atol=1e-9)
    assert np.linalg.norm(sensed, axis=1)[links.index("left/hand/lh_ffdistal")] > 0.1
    assert float(env.view.link_forces("cube", "right").abs().max()) == 0.0


def test_link_forces_need_the_task_to_ask_for_them():
    env = _fresh("PickCube")
    with pytest.raises(KeyError, match="link_force_bodies"):
        env.view.link_forces("cube", "right")


def _depth_for(env, force: float) -> float:
    """The press depth (m) at which the left index tip's force on the cube is `force`."""
    lo, hi = 0.0, 0.01
    for _ in range(30):
        mid = (lo + hi) / 2
        _state(env, left=mid)
        lo, hi = (mid, hi) if _strongest(env, "left") < force else (lo, mid)
    return (lo + hi) / 2


def test_each_clause_of_the_handover_rule():
    env = _fresh("BimanualHandover")
    _state(env, left=None)
    assert not _ok(env), "nobody holds it"
    depth = _depth_for(env, GRIP_FORCE)
    _state(env, left=depth + 2e-4)
    assert _strongest(env, "left") >= GRIP_FORCE and _ok(env)
    _state(env, left=depth - 2e-4)
    assert 0.0 < _strongest(env, "left") < GRIP_FORCE
    assert not _ok(env), "a grip under 1.6 N"
    _state(env, left=depth + 2e-4, right=0.002)
    assert _strongest(env, "left") >= GRIP_FORCE and _strongest(env, "right") > 0.0
    assert not _ok(env), "the right hand still touches the cube"
    _state(env, left=depth + 2e-4)
    free = env.scene.model.joint("cube/free").dofadr[0]
    env.sim.field("qvel")[0, free + 2] = -1.0
    _settle(env)
    assert not _ok(env), "the cube is falling"


@functools.cache
def _backend_env(backend: str):
    return make_env("BimanualHandover", num_envs=1, seed=0, backend=backend, nthread=1)


def test_warp_link_forces_match_the_cpu_backend():
    pytest.importorskip("mujoco_warp")
    cpu = _backend_env("cpu")
    _state(cpu, left=0.004, right=0.002)
    state = cpu.sim.get_state()
    gpu = _backend_env("warp")
    gpu.reset()
    gpu.sim.set_state(torch.arange(1), state, acceleration=True)
    forces = {name: [env.view.link_forces("cube", s)[0].double().cpu().numpy()
                     for s in ("left", "right")] for name, env in (("cpu", cpu), ("warp", gpu))}
    for cpu, gpu in zip(forces["cpu"], forces["warp"], strict=True):
        assert np.linalg.norm(cpu, axis=1).max() > 0.5
        np.testing.assert_allclose(np.linalg.norm(gpu, axis=1), np.linalg.norm(cpu, axis=1),
                                   rtol=0.05, atol=0.05)
