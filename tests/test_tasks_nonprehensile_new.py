"""PushSphereUpSlope, PivotLargeCuboidAgainstWall and TakeBookOffShelf: a state that
satisfies each success predicate and, per clause of the paper's condition, a near miss
that does not."""

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


def _set_pose(env, obj: str, pos, quat=(1.0, 0.0, 0.0, 0.0), speed: float = 0.0) -> None:
    joint = env.scene.model.joint(env.task.objects[obj].free_joint)
    adr, vadr = joint.qposadr[0], joint.dofadr[0]
    env.sim.field("qpos")[0, adr : adr + 7] = torch.tensor([*pos, *quat], dtype=torch.float64)
    env.sim.field("qvel")[0, vadr : vadr + 6] = torch.tensor([speed, 0, 0, 0, 0, 0],
                                                             dtype=torch.float64)


def _ok(env) -> bool:
    env.sim.forward(torch.arange(env.num_envs))
    return bool(env.task.success(env.view)[0])


def _about(axis, angle: float, base=(1.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    """`base` (w, x, y, z) turned by `angle` (rad) about its own `axis`."""
    turn, out = np.zeros(4), np.zeros(4)
    mujoco.mju_axisAngle2Quat(turn, np.asarray(axis, dtype=float), angle)
    mujoco.mju_mulQuat(out, np.asarray(base, dtype=float), turn)
    return out


def test_push_sphere_up_slope_within_8cm_of_a_goal_on_the_plateau():
    env = _env("PushSphereUpSlope")
    env.reset()
    goal = env.view.goal[0, :3].numpy().copy()
    crest = env.view.point_pos(*env.task.objects["ramp"].points["target"])[0].numpy()
    uphill = env.view.axis(*env.task.objects["ramp"].axes["uphill"])[0].numpy()
    assert 0.0 < (goal - crest) @ uphill < 0.1, "just past the crest"
    assert not _ok(env), "the ball starts before the slope"
    _set_pose(env, "sphere", goal + [0.05, 0.05, 0.0])
    assert _ok(env)
    _set_pose(env, "sphere", goal - 0.09 * uphill)
    assert not _ok(env), "9 cm short of the goal"


def test_push_sphere_up_slope_goals_spread_across_the_slope():
    env = make_env("PushSphereUpSlope", num_envs=8, seed=3)
    env.reset()
    goal = env.view.goal[:, :3].numpy()
    ramp = env.view.body_pos("ramp").numpy()
    uphill = env.view.axis(*env.task.objects["ramp"].axes["uphill"]).numpy()
    across = np.stack([-uphill[:, 1], uphill[:, 0]], 1)
    side = ((goal - ramp)[:, :2] * across).sum(1)
    assert np.all(np.abs(side) <= 0.15 + 1e-9) and np.ptp(side) > 0.1


def test_pivot_board_lifted_20cm_and_within_20_deg_of_vertical():
    env = _env("PivotLargeCuboidAgainstWall")
    env.reset()
    start = env.view.body_pos("board")[0].numpy().copy()
    yaw = env.view.body_quat("board")[0].numpy().copy()
    standing = _about((0, 1, 0), -math.pi / 2, yaw)  # its long x axis up
    assert not _ok(env), "lying flat"
    _set_pose(env, "board", start + [0, 0, 0.23], standing)
    assert _ok(env)
    assert env.task.lift(env.view, "board")[0] >= 0.2
    _set_pose(env, "board", start + [0, 0, 0.23], _about((0, 1, 0), -math.radians(72), yaw))
    assert _ok(env), "18 deg off vertical"
    _set_pose(env, "board", start + [0, 0, 0.23], _about((0, 1, 0), math.radians(75), yaw))
    assert _ok(env), "the other end up"
    _set_pose(env, "board", start + [0, 0, 0.22], _about((0, 1, 0), -math.radians(65), yaw))
    assert not _ok(env), "25 deg off vertical"
    _set_pose(env, "board", start + [0, 0, 0.19], standing)
    assert not _ok(env), "upright but lifted only 19 cm"
    _set_pose(env, "board", start + [0, 0, 0.23], standing, speed=1.0)
    assert not _ok(env), "flung through the pose"


def test_take_book_within_5cm_and_26_deg_of_the_goal_pose():
    env = _env("TakeBookOffShelf")
    env.reset()
    start = env.view.body_pos("book")[0].numpy().copy()
    goal = env.view.goal[0].numpy().copy()
    out = env.view.axis(*env.task.objects["shelf"].axes["out"])[0].numpy()
    assert np.allclose(goal[:3] - start, 0.18 * out + [0, 0, 0.05], atol=1e-9)
    up = np.zeros(9)
    mujoco.mju_quat2Mat(up, goal[3:])
    assert math.isclose(math.degrees(math.acos(up[8])), 65.0, abs_tol=1e-6), "tipped 65 deg"
    assert up.reshape(3, 3)[:, 2] @ out > 0.0, "its top towards the hand"
    assert not _ok(env), "still in the shelf"
    _set_pose(env, "book", goal[:3] + [0.03, 0.0, 0.03], goal[3:])
    assert _ok(env)
    _set_pose(env, "book", goal[:3], _about((0, 1, 0), math.radians(22), goal[3:]))
    assert _ok(env), "22 deg off"
    _set_pose(env, "book", goal[:3], _about((0, 1, 0), math.radians(30), goal[3:]))
    assert not _ok(env), "30 deg off"
    _set_pose(env, "book", goal[:3] + [0.0, 0.0, 0.055], goal[3:])
    assert not _ok(env), "5.5 cm off"
    _set_pose(env, "book", start + 0.18 * out + [0, 0, 0.05])
    assert not _ok(env), "at the goal's place but upright"
