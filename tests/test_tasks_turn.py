"""RotateKnob and GraspBucket: they build and reset unsolved, and their predicates hold
exactly where the paper's do (joint state set directly): the knob at either end of its
180 deg travel but not at 170 deg, the bail raised 40% of its reachable range from its
near-limit rest but not 36%."""

import math

from test_tasks import _fresh, _ok, _set_joint

from dexbench.tasks.plans import TurnPlan


def _success(env, joint: str, value: float) -> bool:
    _set_joint(env, joint, value)
    return _ok(env)


def test_knob_resets_in_the_middle_and_succeeds_at_either_end():
    env = _fresh("RotateKnob")
    joint = env.task.joint
    lo, hi = env.task.objects["knob"].joints[joint]
    assert math.isclose(hi - lo, math.pi) and env.task.initial_joints[joint] == 0.0
    assert isinstance(env.task.expert, TurnPlan)
    assert not env.task.success(env.view).any()
    assert _success(env, joint, hi) and _success(env, joint, lo), "both ends count"
    # 170 deg of the 180 (10 deg short of an end), either way, is not at the end.
    assert not _success(env, joint, lo + math.radians(170.0))
    assert not _success(env, joint, hi - math.radians(170.0))


def test_bucket_resets_near_its_stop_and_succeeds_at_40_percent():
    env = _fresh("GraspBucket")
    joint = env.task.joint
    lo, hi = env.task.objects["bucket"].joints[joint]
    q0 = env.task.initial_joints[joint]
    assert lo < q0 < lo + math.radians(5.0), "resting near its lower stop"
    assert not env.task.success(env.view).any()
    reach = hi - q0
    assert _success(env, joint, q0 + 0.42 * reach)
    assert not _success(env, joint, q0 + 0.36 * reach), "near miss: bail not raised enough"


def test_bail_rests_on_its_stop_when_left_alone():
    """No spring: left alone for 1 s the bail falls onto its stop and the pail stays put."""
    env = _fresh("GraspBucket")
    action = env.home_action.repeat(env.num_envs, 1)
    for _ in range(60):
        env.step(action)
    lo = env.task.objects["bucket"].joints[env.task.joint][0]
    assert (env.view.joint_pos(env.task.joint) - lo).abs().max() < 0.02
    assert not env.task.success(env.view).any()
