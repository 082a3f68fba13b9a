"""NutThread, InsertGear and PlugCharger: a state that satisfies each success predicate
and, per clause of the paper's condition, a near miss that does not; and the thread's
mechanism (the nut gets down only by turning, and nothing but the nut drives it)."""

import functools
import math

import mujoco
import numpy as np
import torch

from dexbench.tasks.registry import make_env


@functools.cache
def _env(name: str):
    env = make_env(name, num_envs=1, seed=0)
    env.reset()
    return env


def _qadr(env, joint: str) -> int:
    return int(env.scene.model.joint(joint).qposadr[0])


def _set_pose(env, obj: str, pos, quat=(1.0, 0.0, 0.0, 0.0)) -> None:
    adr = _qadr(env, env.task.objects[obj].free_joint)
    env.sim.field("qpos")[0, adr : adr + 7] = torch.tensor([*pos, *quat], dtype=torch.float64)


def _point(env, obj: str, point: str) -> np.ndarray:
    return env.view.point_pos(*env.task.objects[obj].points[point])[0].numpy().copy()


def _axis(env, obj: str, axis: str) -> np.ndarray:
    return env.view.axis(*env.task.objects[obj].axes[axis])[0].numpy().copy()


def _ok(env) -> bool:
    env.sim.forward(torch.arange(env.num_envs))
    return bool(env.task.success(env.view)[0])


def _yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    return (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))


def _set_thread(env, turned: float) -> None:
    """The follower turned `turned` (rad, negative: down) and advanced to match."""
    pitch = 0.008
    env.sim.field("qpos")[0, _qadr(env, "bolt/thread")] = turned
    env.sim.field("qpos")[0, _qadr(env, "bolt/advance")] = pitch * turned / (2 * math.pi)
    env.sim.forward(torch.arange(1))


def _nut_bottom_at(env, where, yaw: float = 0.0) -> None:
    _set_pose(env, "nut", np.asarray(where) + [0.0, 0.0, 0.02], _yaw_quat(yaw))


def test_nut_thread_centred_and_threaded_down():
    env = _env("NutThread")
    env.reset()
    _set_thread(env, -3 * math.pi)
    seated = _point(env, "bolt", "seated")
    assert np.allclose(_point(env, "bolt", "start"), seated, atol=2e-4), "1.5 turns = 12 mm"
    _nut_bottom_at(env, seated + [0.0, 0.0, 0.001])
    assert _ok(env)
    _nut_bottom_at(env, seated + [0.0, 0.0, 0.004])
    assert not _ok(env), "0.4 turns short of the depth"
    _nut_bottom_at(env, seated + [0.003, 0.0, 0.0])
    assert not _ok(env), "off the bolt's axis"
    _set_thread(env, 0.0)
    _nut_bottom_at(env, _point(env, "bolt", "start"))
    assert not _ok(env), "on the thread but not turned down"
    assert bool(env.task.on_key(env.view)[0])


def _settle(model, data, seconds: float, torque: float = 0.0, press: float = 0.0) -> None:
    """Step the raw physics with a torque about z (N m) and a downward press (N) on the
    nut, both ramped up over the first quarter second, the hand out of the way."""
    body = model.body("nut").id
    steps = round(seconds / model.opt.timestep)
    for k in range(steps):
        ramp = min(1.0, k * model.opt.timestep / 0.25)
        data.xfrc_applied[body] = [0, 0, -press * ramp, 0, 0, torque * ramp]
        mujoco.mj_step(model, data)


def _raw_env():
    env = make_env("NutThread", num_envs=1, seed=0)
    env.reset()
    model, data = env.scene.model, env.sim.batch.get_data(0)
    data.qpos[:] = env.sim.field("qpos")[0].numpy()
    data.ctrl[:] = env.sim.field("ctrl")[0].numpy()  # the hand holds its start pose, up high
    return env, model, data


def _nut_over_key(yaw_off: float, above: float):
    """The raw env with the nut `above` m over the follower's top, turned `yaw_off` from
    the key's flats; also the follower's body id and its top at rest."""
    _, model, data = _raw_env()
    mujoco.mj_forward(model, data)
    follower = model.body("bolt/follower").id
    top = data.xpos[follower].copy()
    key = data.xmat[follower].reshape(3, 3)[:, 0]
    yaw = math.atan2(key[1], key[0]) + yaw_off
    adr = int(model.joint("nut/free").qposadr[0])
    data.qpos[adr : adr + 7] = [*(top + [0, 0, above]), *_yaw_quat(yaw)]
    mujoco.mj_forward(model, data)
    return model, data, follower, top


def test_nut_goes_down_only_when_turned():
    model, data, follower, top = _nut_over_key(0.0, 0.02 + 0.0002)
    _settle(model, data, 1.0, press=8.0)
    assert abs(data.xpos[model.body("nut").id][2] - 0.02 - data.xpos[follower][2]) < 0.002
    assert data.xpos[follower][2] > top[2] - 0.001, "pressed without turning: it stays up"
    _settle(model, data, 2.0, torque=-0.05, press=0.5)
    drop = top[2] - data.xpos[follower][2]
    assert drop > 0.011, f"turned clockwise it goes down the thread ({drop * 1e3:.1f} mm)"
    assert abs(data.xpos[model.body("nut").id][2] - 0.02 - data.xpos[follower][2]) < 0.002


def test_nut_with_flats_crossed_sits_on_the_key():
    model, data, _, top = _nut_over_key(math.pi / 6, 0.012 + 0.02 + 0.001)
    _settle(model, data, 0.5, press=2.0)
    height = data.xpos[model.body("nut").id][2] - 0.02 - top[2]
    assert height > 0.010, "the hex bore does not go over the key 30 deg off"


def test_thread_follower_touches_only_the_nut():
    env = _env("NutThread")
    model = env.scene.model
    follower = model.body("bolt/follower").id
    nut = model.body("nut").id
    for g in range(model.ngeom):
        if model.geom_bodyid[g] != follower:
            continue
        for h in range(model.ngeom):
            other = model.geom_bodyid[h]
            if other in (follower, model.body("bolt").id):
                continue
            meets = (model.geom_contype[g] & model.geom_conaffinity[h]) or (
                model.geom_contype[h] & model.geom_conaffinity[g])
            assert bool(meets) == (other == nut), model.body(other).name


def test_insert_gear_centred_and_seated():
    env = _env("InsertGear")
    env.reset()
    seat = _point(env, "base", "seat")
    _set_pose(env, "gear", seat + [0.0, 0.0, 0.02 + 0.002])
    assert _ok(env)
    _set_pose(env, "gear", seat + [0.0, 0.0, 0.02 + 0.005])
    assert not _ok(env), "5 mm short of full depth"
    _set_pose(env, "gear", seat + [0.003, 0.0, 0.02])
    assert not _ok(env), "3 mm off the shaft"


def test_plug_charger_inserted_and_aligned():
    env = _env("PlugCharger")
    env.reset()
    out = _axis(env, "socket", "bore")
    entrance = _point(env, "socket", "entrance")
    yaw = math.atan2(-out[1], -out[0])
    side = np.cross(out, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    quat = _yaw_quat(yaw)
    tip_local = np.array(env.task.objects["plug"].points["tip"][1])

    def tip_at(where) -> None:
        rot = np.array([[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0],
                        [0, 0, 1]])
        _set_pose(env, "plug", np.asarray(where) - rot @ tip_local, quat)

    tip_at(entrance - 0.02 * out)
    assert _ok(env)
    assert np.allclose(_point(env, "plug", "tip"), entrance - 0.02 * out, atol=1e-6)
    tip_at(entrance - 0.01 * out)
    assert not _ok(env), "only half the pin in"
    tip_at(entrance - 0.02 * out + 0.003 * side)
    assert not _ok(env), "3 mm to the side"
    tip_at(entrance - 0.02 * out + [0.0, 0.0, 0.003])
    assert not _ok(env), "3 mm high"
