"""PourWineGlass: each clause of the paper's rule (lift, tilt, opening not touched), one
near miss per clause, a touch below the opening that still counts, and the glass itself
(its rim band a zone body of its own, standing steady on its foot)."""

from test_tasks import _forward, _fresh, _ok, _place_point, _quat_about
from test_tasks_pour_new import _check_rim_band, _press_hand_on

from dexbench.assets import glassware


def _pose(env, lift: float, tilt: float) -> None:
    """The glass tilted `tilt` deg about y, its root `lift` m above its reset height."""
    root = env.task.objects["glass"].root
    start = env.view.initial_body_pos[root][0].numpy().copy()
    _place_point(env, "glass", "bottom", start + [0.0, 0.0, lift], _quat_about("y", tilt))
    _forward(env)


def _geom(env, name: str) -> int:
    return env.scene.model.geom(name).id


def _touching(env, geom: int) -> bool:
    _forward(env)
    data = env.sim.batch.get_data(0)
    return any(geom in (c.geom1, c.geom2) for c in data.contact[: data.ncon])


def test_each_clause_of_the_pour_rule():
    env = _fresh("PourWineGlass")
    assert env.view.goal is None, "the paper pours nowhere in particular"
    assert not _ok(env), "unsolved at reset"
    _pose(env, lift=0.23, tilt=115.0)
    assert _ok(env)
    _pose(env, lift=0.18, tilt=115.0)
    assert not _ok(env), "not lifted enough"
    _pose(env, lift=0.23, tilt=95.0)
    assert not _ok(env), "not tilted enough"
    _pose(env, lift=0.23, tilt=115.0)
    rim = _geom(env, "glass/rim_0")
    _press_hand_on(env, rim)
    assert _touching(env, rim)
    assert not _ok(env), "a hand touches the opening"


def test_glass_touched_below_its_opening_still_pours():
    env = _fresh("PourWineGlass")
    _pose(env, lift=0.23, tilt=115.0)
    for name in ("glass/stem", "glass/wall4_0"):
        _pose(env, lift=0.23, tilt=115.0)
        _press_hand_on(env, _geom(env, name))
        assert _touching(env, _geom(env, name)), name
        assert _ok(env), name


def test_rim_band_is_its_own_zone_body_at_the_top_of_the_bowl():
    _check_rim_band(glassware.add_wine_glass, "glass", 0.17)


def test_glass_stands_still_on_its_foot():
    env = _fresh("PourWineGlass")
    root = env.task.objects["glass"].root
    start = env.view.body_pos(root)[0].clone()
    action = env.home_action.repeat(env.num_envs, 1)
    for _ in range(60):
        env.step(action)
    assert float((env.view.body_pos(root)[0] - start).norm()) < 1e-3
    assert float(env.task._tilt(env.view)[0]) < 1.0
