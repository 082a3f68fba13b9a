"""BimanualLiftDutchOven and BimanualLiftBasket: they build and reset unsolved, carry a
two-hand plan, and their predicates hold exactly where the paper's do (object pose set
directly): the oven lifted 0.30 m but not 0.28 m; the basket lifted 0.20 m within 10 deg
of level but neither 0.18 m nor tilted 12 deg; either thrown (0.6 m/s) is no lift."""

from test_tasks import _fresh, _initial, _lifted, _ok, _quat_about

from dexbench.tasks.plans import TwoHandPlan


def _moving(env, obj: str, speed: float) -> None:
    """Give object `obj` an upward velocity `speed` (m/s)."""
    adr = env.scene.model.joint(env.task.objects[obj].free_joint).dofadr[0]
    env.sim.field("qvel")[0, adr + 2] = speed


def test_dutch_oven_lifted_030():
    env = _fresh("BimanualLiftDutchOven")
    assert env.task.bimanual and env.task.episode_seconds == 10.0
    assert isinstance(env.task.expert, TwoHandPlan)
    assert not env.task.success(env.view).any()
    assert _initial(env, "oven")[2] < 0.61, "rests on the table"
    _lifted(env, "oven", 0.31, _quat_about("x", 20))
    assert _ok(env), "no level clause: a tilted oven lifted high enough counts"
    _lifted(env, "oven", 0.28)
    assert not _ok(env), "not lifted high enough"
    _lifted(env, "oven", 0.31)
    _moving(env, "oven", 0.6)
    assert not _ok(env), "thrown, not lifted"


def test_basket_lifted_020_and_level():
    env = _fresh("BimanualLiftBasket")
    assert env.task.bimanual and env.task.episode_seconds == 10.0
    assert isinstance(env.task.expert, TwoHandPlan)
    assert not env.task.success(env.view).any()
    _lifted(env, "basket", 0.21, _quat_about("y", 8))
    assert _ok(env)
    _lifted(env, "basket", 0.21, _quat_about("x", 12))
    assert not _ok(env), "not level"
    _lifted(env, "basket", 0.18)
    assert not _ok(env), "not lifted high enough"
    _lifted(env, "basket", 0.21)
    _moving(env, "basket", 0.6)
    assert not _ok(env), "thrown, not lifted"
