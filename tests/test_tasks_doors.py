"""The door tasks: OpenDoor's latch really holds the door until its lever is turned, and
its predicate holds just past 80% of the swing; OpenDoubleDoor needs both doors past 80%
with the moments each went past at most 1.0 s apart, kept in the simulator state."""

import math

import mujoco
import numpy as np
import pytest
import torch
from test_tasks import _forward, _fresh, _ok, _set_joint

from dexbench.tasks.plans import BothHandsPlan, SwingPlan

DOOR, LEVER = "door/door", "door/lever"
DOUBLE = ("cabinet/a/door", "cabinet/b/door")


def _set(env, joint: str, q: float) -> None:
    _set_joint(env, joint, q)
    _forward(env)


def _scratch(env) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """A copy of env 0's state to push on with applied forces, hands holding home."""
    model = env.scene.model
    data = mujoco.MjData(model)
    data.qpos[:] = env.sim.field("qpos")[0].numpy()
    data.mocap_pos[:] = env.sim.field("mocap_pos")[0].numpy()
    data.mocap_quat[:] = env.sim.field("mocap_quat")[0].numpy()
    data.ctrl[:] = env.home_action.numpy()
    mujoco.mj_forward(model, data)
    return model, data


def _pull(env, lever_torque: float, seconds: float = 1.0, force: float = 20.0) -> float:
    """The door's angle (rad) after turning its lever by `lever_torque` N m for 0.3 s,
    then, still turning it, pulling its grip straight out from the door with `force` N
    for `seconds`."""
    model, data = _scratch(env)
    lever = model.body(LEVER)
    handle = env.task.objects["door"].points["handle"][1]
    dof = model.joint(LEVER).dofadr[0]
    turn = round(0.3 / model.opt.timestep)
    for _ in range(turn):
        data.qfrc_applied[dof] = lever_torque
        mujoco.mj_step(model, data)
    for _ in range(round(seconds / model.opt.timestep)):
        rot = data.xmat[lever.id].reshape(3, 3)
        point = data.xpos[lever.id] + rot @ np.asarray(handle)
        outward = data.xmat[model.body("door/door").id].reshape(3, 3)[:, 0]
        data.qfrc_applied[:] = 0.0
        mujoco.mj_applyFT(model, data, force * outward, np.zeros(3), point, lever.id,
                          data.qfrc_applied)
        data.qfrc_applied[dof] += lever_torque
        mujoco.mj_step(model, data)
    return float(data.qpos[model.joint(DOOR).qposadr[0]])


def test_door_resets_closed_and_succeeds_past_80_percent():
    env = _fresh("OpenDoor")
    lo, hi = env.task.joint_range(DOOR)
    assert env.task.initial_joints[DOOR] == lo == 0.0 and hi > math.radians(80)
    assert env.task.initial_joints[LEVER] == 0.0
    plan = env.task.expert
    assert isinstance(plan, SwingPlan) and plan.joint == DOOR and plan.latch == LEVER
    assert not _ok(env), "solved at reset"
    _set(env, DOOR, 0.82 * hi)
    assert _ok(env)
    _set(env, DOOR, 0.78 * hi)
    assert not _ok(env)


def test_latched_door_does_not_open_with_the_lever_at_rest():
    """A straight pull on the resting lever presses the cam into the strike post."""
    env = _fresh("OpenDoor")
    assert _pull(env, lever_torque=0.0) < math.radians(1.0)


def test_latched_door_opens_once_the_lever_is_turned():
    """The same pull with the lever held at its stop swings the door open."""
    env = _fresh("OpenDoor")
    assert _pull(env, lever_torque=1.0) > math.radians(30.0)


def test_lever_springs_back():
    env = _fresh("OpenDoor")
    _set(env, LEVER, math.radians(50.0))
    model, data = _scratch(env)
    for _ in range(round(0.5 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    assert data.qpos[model.joint(LEVER).qposadr[0]] < math.radians(2.0)


def _double(env, qa: float, qb: float, since: tuple[int, int], now: int = 500) -> bool:
    """Doors at `qa`, `qb` (fractions of their range), gone past 80% at control steps
    `since` (0: not past), `now` steps into the episode."""
    for joint, q in zip(DOUBLE, (qa, qb), strict=True):
        _set_joint(env, joint, q * env.task.joint_range(joint)[1])
    env.view.memory[0] = torch.tensor([now, *since], dtype=env.view.memory.dtype)
    return _ok(env)


def test_double_door_needs_both_doors_past_80_percent():
    env = _fresh("OpenDoubleDoor")
    assert isinstance(env.task.expert, BothHandsPlan)
    assert set(env.task.expert.hands) == {"left", "right"}
    assert all(env.task.initial_joints[j] == 0.0 for j in DOUBLE)
    assert not _ok(env), "solved at reset"
    assert _double(env, 0.82, 0.82, (400, 410))
    assert not _double(env, 0.82, 0.78, (400, 410))
    assert not _double(env, 0.78, 0.82, (400, 410))


def test_double_door_gap_at_most_one_second():
    env = _fresh("OpenDoubleDoor")
    steps = round(1.0 / env.view.control_dt)
    assert _double(env, 0.82, 0.82, (300, 300 + steps))
    assert not _double(env, 0.82, 0.82, (300, 300 + steps + 1))
    assert not _double(env, 0.82, 0.82, (300 + steps + 1, 300))


@pytest.mark.parametrize("late", [0.5, 1.5])
def test_double_door_memory_records_when_each_door_stays_past(late):
    """`update` (after every control step) notes when each door goes past 80% and
    forgets it when the door falls back; a door past for 1.5 s before the other fails."""
    env = _fresh("OpenDoubleDoor")
    env.view.memory[0] = 0.0

    def step(qa: float, qb: float) -> None:
        for joint, q in zip(DOUBLE, (qa, qb), strict=True):
            _set_joint(env, joint, q * env.task.joint_range(joint)[1])
        _forward(env)
        env.task.update(env.view)

    step(0.82, 0.1)
    assert env.view.memory[0, 1] == 1 and env.view.memory[0, 2] == 0
    step(0.5, 0.1)  # fell back: forgotten
    assert env.view.memory[0, 1] == 0
    step(0.82, 0.1)
    went = int(env.view.memory[0, 1])
    for _ in range(round(late / env.view.control_dt) - 1):
        step(0.82, 0.1)
    step(0.82, 0.82)
    assert env.view.memory[0, 1] == went
    assert bool(env.task.success(env.view)[0]) == (late <= 1.0)
    assert env.task.state_obs(env.view).shape[1] > 2
    assert np.isclose(float(env.task.state_obs(env.view)[0, -2]), late + env.view.control_dt)
