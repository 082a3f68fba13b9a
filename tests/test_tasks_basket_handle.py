"""LiftBasketHandle: it builds and resets unsolved with both handles folded on their
stops, and its predicate holds exactly where the paper's does (joint state set
directly): either handle raised 50% of the way from its folded reset counts, 45% does
not; left alone, the handles stay folded."""

from test_tasks import _fresh, _ok, _set_joint

from dexbench.tasks.plans import HoldActuatePlan

JOINTS = ("basket/handle0", "basket/handle1")


def test_basket_handle_raised_half_way_either():
    env = _fresh("LiftBasketHandle")
    task = env.task
    assert task.bimanual and task.episode_seconds == 8.0
    assert isinstance(task.expert, HoldActuatePlan) and task.joints == JOINTS
    assert not task.success(env.view).any()
    for joint in JOINTS:
        lo, hi = task.objects["basket"].joints[joint]
        assert task.initial_joints[joint] == lo, "folded on its stop"
        _set_joint(env, joint, lo + 0.52 * (hi - lo))
        assert _ok(env), joint
        _set_joint(env, joint, lo + 0.45 * (hi - lo))
        assert not _ok(env), f"{joint} not raised half way"
        _set_joint(env, joint, lo)


def test_basket_handles_stay_folded_when_left_alone():
    env = _fresh("LiftBasketHandle")
    action = env.home_action.repeat(env.num_envs, 1)
    for _ in range(60):
        env.step(action)
    for joint in JOINTS:
        lo = env.task.objects["basket"].joints[joint][0]
        assert (env.view.joint_pos(joint) - lo).abs().max() < 0.02
    assert not env.task.success(env.view).any()
