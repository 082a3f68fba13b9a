"""LiftBucket: it builds and resets unsolved with the bail lying near its stop, and its
predicate holds exactly where the paper's does (pose set directly): the bucket lifted
0.12 m above its spawn height but not 0.10 m, and not thrown (0.6 m/s)."""

import math

from test_tasks import _fresh, _initial, _lifted, _ok, _set_joint

from dexbench.tasks.plans import GraspPlan


def test_bucket_lifted_012():
    env = _fresh("LiftBucket")
    task = env.task
    assert task.category == "functional" and task.episode_seconds == 20.0
    assert isinstance(task.expert, GraspPlan) and task.focus_point == ("bucket", "grip")
    lo = task.objects["bucket"].joints["bucket/handle"][0]
    assert lo < task.initial_joints["bucket/handle"] < lo + math.radians(5.0)
    assert not task.success(env.view).any()
    assert _initial(env, "bucket")[2] < 0.61, "rests on the table"
    _lifted(env, "bucket", 0.13)
    _set_joint(env, "bucket/handle", 0.0)
    assert _ok(env), "lifted by the upright bail"
    _lifted(env, "bucket", 0.10)
    assert not _ok(env), "not lifted high enough"
    _lifted(env, "bucket", 0.13)
    adr = env.scene.model.joint(task.objects["bucket"].free_joint).dofadr[0]
    env.sim.field("qvel")[0, adr + 2] = 0.6
    assert not _ok(env), "thrown, not lifted"
