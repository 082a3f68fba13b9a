"""GraspCup, FunctionalPourCan, GraspBleach and GraspKettle: each clause of the paper's
success rule (lift, tilt, outlet near the goal, no-touch zone), one near miss per clause,
and the cup's rim band as a zone body of its own."""

import math

import mujoco
import numpy as np
import pytest
from test_tasks import _forward, _fresh, _ok, _place_point, _point, _quat_about, _set_joint

from dexbench.assets import procedural
from dexbench.assets.objects import new_spec

# task, vessel, outlet, lift threshold (m), tilt threshold (deg), tolerance (m), horizontal
POUR_TASKS = [
    ("GraspCup", "cup", "rim", 0.30, 100.0, 0.10, False),
    ("FunctionalPourCan", "can", "lip", 0.20, 100.0, 0.10, False),
    ("GraspBleach", "bleach", "nozzle", 0.30, 100.0, 0.02, True),
    ("GraspKettle", "kettle", "spout", 0.15, 45.0, 0.05, True),
]


def _target(env) -> np.ndarray:
    """Where the outlet must get to: the sampled goal, or 15 cm over the kettle's mug."""
    if env.view.goal is None:
        return _point(env, "mug", "rim") + [0.0, 0.0, 0.15]
    return env.view.goal[0].numpy()[:3]


def _pose(env, vessel, outlet, lift, tilt, offset=(0.0, 0.0, 0.0)):
    """The outlet at the target (+ `offset`), tilted `tilt` deg, lifted `lift` m."""
    _place_point(env, vessel, outlet, _target(env) + np.asarray(offset), _quat_about("y", tilt))
    _forward(env)
    root = env.task.objects[vessel].root
    env.view.initial_body_pos[root][0, 2] = float(env.view.body_pos(root)[0, 2]) - lift


def _press_hand_on(env, geom: int) -> None:
    """Move the floating wrist so that the hand's last collision geom sits on `geom`."""
    _forward(env)
    target = env.sim.field("geom_xpos")[0, geom].numpy()
    tip = env.view.hand_geom_pos()[0, -1].numpy()
    qpos = env.sim.field("qpos")[0]
    for i, axis in enumerate("xyz"):
        joint = f"right/wrist/{axis}"
        _set_joint(env, joint, float(qpos[env.scene.model.joint(joint).qposadr[0]])
                   + float(target[i] - tip[i]))


def _geoms_of(env, body: str) -> list[int]:
    model = env.scene.model
    return [g for g in range(model.ngeom) if model.geom_bodyid[g] == model.body(body).id]


@pytest.mark.parametrize(("name", "vessel", "outlet", "lift", "tilt", "tol", "horizontal"),
                         POUR_TASKS)
def test_each_clause_of_the_pour_rule(name, vessel, outlet, lift, tilt, tol, horizontal):
    env = _fresh(name)
    good = dict(lift=lift + 0.03, tilt=tilt + 15.0)
    _pose(env, vessel, outlet, **good)
    assert _ok(env)
    _pose(env, vessel, outlet, lift=lift - 0.02, tilt=good["tilt"])
    assert not _ok(env), "not lifted enough"
    _pose(env, vessel, outlet, lift=good["lift"], tilt=tilt - 10.0)
    assert not _ok(env), "not tilted enough"
    _pose(env, vessel, outlet, offset=(tol + 0.01, 0.0, 0.0), **good)
    assert not _ok(env), "outlet too far from the goal"
    # Within the tolerance horizontally, far off vertically: only a horizontal rule passes.
    _pose(env, vessel, outlet, offset=(0.5 * tol, 0.0, 2.0 * tol), **good)
    assert _ok(env) is horizontal
    _pose(env, vessel, outlet, **good)
    _press_hand_on(env, _geoms_of(env, env.task.objects[vessel].zones[0].body)[0])
    assert not _ok(env), "a hand touches the no-touch zone"


def test_kettle_goal_is_the_mug_and_it_follows_it():
    env = _fresh("GraspKettle")
    assert env.view.goal is None and "mug" in env.task.objects
    _pose(env, "kettle", "spout", lift=0.2, tilt=60.0)
    assert _ok(env)
    rim = _point(env, "mug", "rim")
    mug = env.scene.model.joint("mug/free").qposadr[0]
    env.sim.field("qpos")[0, mug] += 0.08  # the mug pushed away: the pour now misses it
    assert not _ok(env)
    assert np.linalg.norm(_point(env, "mug", "rim") - rim) == pytest.approx(0.08)


def test_cup_touched_below_its_rim_band_still_pours():
    env = _fresh("GraspCup")
    _pose(env, "cup", "rim", lift=0.33, tilt=115.0)
    (wall,) = [g for g in _geoms_of(env, "cup") if env.scene.model.geom(g).name == "cup/wall0_4"]
    _press_hand_on(env, wall)
    assert _ok(env)
    data = env.sim.batch.get_data(0)
    assert any(wall in (c.geom1, c.geom2) for c in data.contact[: data.ncon]), "not touching"
    found, _ = env.view.zone_contacts(env.task.objects["cup"].zones[0])
    assert not bool(found.any())


def _check_rim_band(add, name: str, mass: float) -> None:
    """The vessel `add` builds has its opening as one zone body of 16 wall pieces, fixed
    to the vessel, covering the top 1 cm below its `rim` point; the vessel weighs `mass`."""
    spec = new_spec()
    info = add(spec, name)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    (zone,) = info.zones
    band = model.body(zone.body).id
    assert zone.body == f"{name}/rim" and model.body_parentid[band] == model.body(name).id
    assert model.body_jntnum[band] == 0
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == band]
    assert len(geoms) == 16
    centre = data.xpos[band] + zone.pos
    for g in geoms:
        rel = data.geom_xpos[g] - centre
        assert abs(rel[2]) <= zone.half_length and math.hypot(*rel[:2]) <= zone.radius
    rim = info.points["rim"][1][2]
    assert data.xpos[band][2] == pytest.approx(rim - 0.01)
    assert model.body_subtreemass[model.body(name).id] == pytest.approx(mass)


def test_cup_rim_band_is_its_own_zone_body_at_the_top_of_the_wall():
    _check_rim_band(procedural.add_cup, "cup", 0.12)
