"""InsertPipette, PickFromClutter and PickThinObjectFromContainer: a state that satisfies
each success predicate and, per clause of the paper's condition, a near miss that does not;
the clutter starts with nothing interpenetrating.
"""

import functools
import math

import mujoco
import numpy as np
import torch

from dexbench.tasks.contact_pick import CORRAL_HALF, DISTRACTORS, EXTRACT_FORWARD, EXTRACT_RISE
from dexbench.tasks.registry import make_env


@functools.cache
def _env(name: str, n: int = 1):
    env = make_env(name, num_envs=n, seed=0)
    env.reset()
    return env


def _set_pose(env, obj: str, pos, quat=(1.0, 0.0, 0.0, 0.0)) -> None:
    adr = env.scene.model.joint(env.task.objects[obj].free_joint).qposadr[0]
    env.sim.field("qpos")[0, adr : adr + 7] = torch.tensor([*pos, *quat], dtype=torch.float64)
    vadr = env.scene.model.joint(env.task.objects[obj].free_joint).dofadr[0]
    env.sim.field("qvel")[0, vadr : vadr + 6] = 0.0


def _point(env, obj: str, point: str) -> np.ndarray:
    return env.view.point_pos(*env.task.objects[obj].points[point])[0].numpy().copy()


def _ok(env) -> bool:
    env.sim.forward(torch.arange(env.num_envs))
    return bool(env.task.success(env.view)[0])


TIP_DOWN = (math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0)  # +90 deg about y: body +x down
TIP_UP = (math.sqrt(0.5), 0.0, -math.sqrt(0.5), 0.0)


def _tip_at(env, where, quat=TIP_DOWN) -> None:
    """The pipette vertical, its tip at `where` (tip down) or its bulb end there."""
    front = env.task.objects["pipette"].points["tip"][1][0]
    back = -env.task.objects["pipette"].points["bulb_end"][1][0]
    up = front if quat == TIP_DOWN else back
    _set_pose(env, "pipette", np.asarray(where) + [0.0, 0.0, up], quat)


def test_insert_pipette_tip_centred_and_below_the_rim():
    env = _env("InsertPipette")
    rim = _point(env, "flask", "entrance")
    _tip_at(env, rim + [0.005, 0.0, -0.03])
    assert _ok(env)
    assert np.allclose(_point(env, "pipette", "tip"), rim + [0.005, 0.0, -0.03], atol=1e-6)
    _tip_at(env, rim + [0.0, 0.0, -0.005])
    assert not _ok(env), "only 5 mm below the rim"
    _tip_at(env, rim + [0.0, 0.025, -0.03])
    assert not _ok(env), "off the opening's centre"
    _tip_at(env, rim + [0.0, 0.0, -0.03], TIP_UP)
    assert not _ok(env), "the bulb end in the neck, not the tip"


def test_insert_pipette_neck_wall_keeps_an_outside_tip_off_centre():
    """A tip touching the neck's outside is further than 0.02 m from the axis."""
    env = _env("InsertPipette")
    rim = _point(env, "flask", "entrance")
    m, d = env.scene.model, mujoco.MjData(env.scene.model)
    d.mocap_pos[:] = env.sim.field("mocap_pos")[0].numpy()
    d.mocap_quat[:] = env.sim.field("mocap_quat")[0].numpy()
    mujoco.mj_forward(m, d)
    tip = m.geom("pipette/tip").size[0]
    for k in range(32):
        phi = 2 * math.pi * k / 32
        start = rim + [0.05 * math.cos(phi), 0.05 * math.sin(phi), -0.02]
        ray = -np.array([math.cos(phi), math.sin(phi), 0.0])
        geom = np.array([-1], dtype=np.int32)
        dist = mujoco.mj_ray(m, d, start, ray, None, 1, -1, geom)
        assert m.geom(geom[0]).name.startswith("flask/neck")
        assert 0.05 - dist + tip > 0.02, "an outside tip could count as centred"


def test_pick_from_clutter_lift_only_the_target():
    env = _env("PickFromClutter")
    env.reset()
    start = env.view.body_pos("target")[0].numpy().copy()
    _set_pose(env, "target", start + [0.0, 0.0, 0.21])
    assert _ok(env)
    env.reset()
    _set_pose(env, "target", start + [0.0, 0.0, 0.19])
    assert not _ok(env), "only 0.19 m up"
    env.reset()
    other = env.view.body_pos(DISTRACTORS[0])[0].numpy().copy()
    _set_pose(env, DISTRACTORS[0], other + [0.0, 0.0, 0.3])
    assert not _ok(env), "a distractor lifted, not the target"


def test_pick_from_clutter_starts_without_interpenetration():
    env = _env("PickFromClutter", 8)
    env.reset()
    m, d = env.scene.model, mujoco.MjData(env.scene.model)
    clutter = {m.body(env.task.objects[n].root).id for n in ("target", *DISTRACTORS)}
    corral = m.body("corral").id
    for i in range(env.num_envs):
        for f in ("qpos", "mocap_pos", "mocap_quat"):
            getattr(d, f)[:] = env.sim.field(f)[i].numpy()
        mujoco.mj_forward(m, d)
        for c in d.contact[: d.ncon]:
            a, b = m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]
            if a in clutter and (b in clutter or b == corral):
                assert c.dist > -1e-3, (i, m.body(a).name, m.body(b).name, c.dist)
        inside = [np.abs(d.xpos[b][:2] - d.xpos[corral][:2]).max() for b in clutter]
        assert max(inside) < CORRAL_HALF - 0.017, "every centre inside the fence"
    names = {tuple(m.geom(g).rgba) for g in range(m.ngeom)
             if m.geom_bodyid[g] in clutter - {m.body("target").id}}
    assert all(not (g > 0.6 and r < 0.3 and b < 0.3) for r, g, b, _ in names), "a green one"


def test_pick_thin_object_goal_above_and_forward_of_the_start():
    env = _env("PickThinObjectFromContainer")
    env.reset()
    start = _point(env, "plate", "centre")
    goal = env.view.goal[0, :3].numpy()
    assert np.allclose(goal - start, [-EXTRACT_FORWARD, 0.0, EXTRACT_RISE], atol=2e-3)
    root = env.view.body_pos("plate")[0].numpy()
    _set_pose(env, "plate", root + (goal - start) + [0.0, 0.03, 0.0])
    assert _ok(env)
    _set_pose(env, "plate", root + (goal - start) + [0.0, 0.0, -0.05])
    assert not _ok(env), "5 cm short of the goal"
    _set_pose(env, "plate", root)
    assert not _ok(env), "still in the container"
