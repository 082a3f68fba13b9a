"""LiftLid and GraspPot: they build and reset with the lid shut, and succeed exactly when
the lid hinge has covered 80% of its opening range (joint state set directly)."""

import math

import pytest
from test_tasks import _fresh, _ok, _set_joint

LIDS = [("LiftLid", "box"), ("GraspPot", "pot")]


def _success(env, joint: str, value: float) -> bool:
    _set_joint(env, joint, value)
    return _ok(env)


@pytest.mark.parametrize("name, obj", LIDS)
def test_lid_task_resets_shut_and_succeeds_at_80_percent(name, obj):
    env = _fresh(name)
    joint = env.task.joint
    lo, hi = env.task.objects[obj].joints[joint]
    assert lo == 0.0 and math.radians(90.0) <= hi <= math.radians(120.0)
    assert env.task.initial_joints[joint] == 0.0
    assert not env.task.success(env.view).any()
    assert _success(env, joint, 0.82 * hi)
    assert not _success(env, joint, 0.78 * hi), "near miss: lid not quite open enough"
    assert not _success(env, joint, 0.0)


@pytest.mark.parametrize("name, obj", LIDS)
def test_lid_stays_shut_under_its_weight(name, obj):
    """No spring: left alone for 1 s the lid rests on its rim and the container on the
    table."""
    env = _fresh(name)
    action = env.home_action.repeat(env.num_envs, 1)
    for _ in range(60):
        env.step(action)
    q = env.view.joint_pos(env.task.joint)
    assert (q.abs() < 0.01).all()
    assert not env.task.success(env.view).any()
