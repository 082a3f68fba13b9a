"""MicrowaveFood, CookFood, OvenBake and CleanTable: their stage predicates, set up by
placing objects and joints directly (no physics): a state sequence that succeeds, a near
miss per clause, stages done out of order, and a condition broken after it held."""

import math

import numpy as np
import torch
from test_tasks import _forward, _fresh, _initial, _place_point, _quat_about, _set_joint, _set_pose


def _update(env) -> int:
    _forward(env)
    env.task.update(env.view)
    return int(env.task.completed(env.view)[0])


def _ok(env) -> bool:
    return bool(env.task.success(env.view)[0])


def _local_to_world(env, body: str, local) -> np.ndarray:
    view = env.view
    pos = view.body_pos(body)[0].numpy()
    axes = [view.axis(body, e)[0].numpy() for e in ((1.0, 0, 0), (0, 1.0, 0), (0, 0, 1.0))]
    return pos + sum(c * a for c, a in zip(local, axes, strict=True))


def _box_centre(env, holder: str, space: str, up: float = 0.0) -> np.ndarray:
    """World point in the middle of `holder`'s box `space`, `up` m above its floor."""
    body, lo = env.task.objects[holder].points[f"{space}_lo"]
    hi = env.task.objects[holder].points[f"{space}_hi"][1]
    return _local_to_world(env, body, ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2] + up))


def _pour(env, vessel: str, outlet: str, at, tilt: float = 110.0, above: float = 0.05):
    """The vessel tilted `tilt` deg about y, its outlet `above` m over point `at`."""
    _place_point(env, vessel, outlet, np.asarray(at) + [0, 0, above], _quat_about("y", tilt))


def _home(env, obj: str) -> None:
    _set_pose(env, obj, _initial(env, obj))


# --- MicrowaveFood ---------------------------------------------------------------------

def _fraction(env, joint: str, frac: float) -> None:
    lo, hi = env.task.joint_range(joint)
    _set_joint(env, joint, lo + frac * (hi - lo))


def _food_in_microwave(env, off=(0.0, 0.0, 0.0)) -> None:
    _forward(env)
    cavity = env.view.point_pos(*env.task.objects["microwave"].points["cavity"])[0].numpy()
    _set_pose(env, "food", cavity + [0, 0, 0.027] + np.asarray(off))


def test_microwavefood_in_order_with_near_misses():
    env = _fresh("MicrowaveFood")
    fridge, door, dial = "fridge/door", "microwave/door", "microwave/dial1"
    _fraction(env, fridge, 0.22)
    assert _update(env) == 0, "near miss: fridge not a quarter open"
    _fraction(env, fridge, 0.3)
    assert _update(env) == 1
    _set_joint(env, fridge, math.radians(8))
    assert _update(env) == 1, "near miss: fridge not closed"
    _set_joint(env, fridge, 0.0)
    assert _update(env) == 2
    _fraction(env, door, 0.45)
    assert _update(env) == 2, "near miss: microwave not half open"
    _fraction(env, door, 0.6)
    assert _update(env) == 3
    _food_in_microwave(env, (0.0, 0.0, 0.16))
    assert _update(env) == 3, "near miss: food 0.16 m from its goal"
    _food_in_microwave(env)
    assert _update(env) == 4
    _set_joint(env, door, math.radians(8))
    assert _update(env) == 4, "near miss: microwave not closed"
    _set_joint(env, door, 0.0)
    assert _update(env) == 5 and not _ok(env)
    _set_joint(env, dial, math.radians(15))
    assert _update(env) == 5, "near miss: dial turned 15 deg"
    _set_joint(env, dial, math.radians(20))
    assert _update(env) == 6 and _ok(env)
    assert float(env.task.state_obs(env.view)[0, -1]) == 1.0
    _set_joint(env, door, math.radians(30))
    _forward(env)
    assert not _ok(env), "the microwave must stay closed"
    _set_joint(env, door, 0.0)
    _home(env, "food")
    _forward(env)
    assert not _ok(env), "the food must stay in the microwave"


def test_microwavefood_out_of_order_fails():
    env = _fresh("MicrowaveFood")
    _fraction(env, "microwave/door", 0.6)
    _food_in_microwave(env)
    _update(env)
    _set_joint(env, "microwave/door", 0.0)
    _set_joint(env, "microwave/dial0", math.radians(30))
    assert _update(env) == 0 and not _ok(env), "the fridge was never opened"
    _fraction(env, "fridge/door", 0.3)
    _update(env)
    _set_joint(env, "fridge/door", 0.0)
    assert _update(env) == 2
    assert _update(env) == 2, "the microwave must open after the fridge is closed"


# --- CookFood --------------------------------------------------------------------------

def _mouth(env) -> np.ndarray:
    _forward(env)
    return env.view.point_pos(*env.task.objects["pot"].points["mouth"])[0].numpy()


def _pot_on_stove(env, off=(0.0, 0.0, 0.0), tilt: float = 0.0, spill: bool = False) -> None:
    """The pot (upright, yaw 0) with its centre on the burner, the food in it."""
    _forward(env)
    target = env.view.point_pos(*env.task.objects["stove"].points["target"])[0].numpy()
    pos = target + np.asarray(off)
    _set_pose(env, "pot", pos, _quat_about("y", tilt))
    for k, name in enumerate(env.task.ingredients):
        slot = np.asarray(env.task.objects["pot"].points[f"slot{k}"][1])
        _set_pose(env, name, pos + slot + ([0.3, 0, 0] if spill and k == 1 else 0))


def test_cookfood_pours_in_any_order_then_cooks():
    env = _fresh("CookFood")
    parts = env.task.part_conditions
    _pour(env, "can", "lip", _mouth(env), tilt=95.0)
    _forward(env)
    assert not parts(env.view)[0, 1], "near miss: tilted 95 deg"
    _pour(env, "can", "lip", _mouth(env) + [0.11, 0, 0])
    _forward(env)
    assert not parts(env.view)[0, 1], "near miss: spout 0.11+ m from the pot"
    _pour(env, "can", "lip", _mouth(env), above=-0.03)
    _forward(env)
    assert not parts(env.view)[0, 1], "near miss: lifted only ~0.09 m"
    _pour(env, "can", "lip", _mouth(env))
    assert _update(env) == 0 and float(env.task.progress(env.view)[0]) == 0.25
    _home(env, "can")
    _pour(env, "bottle", "top", _mouth(env))
    assert _update(env) == 1, "the can first, then the bottle: any order"
    _home(env, "bottle")
    _set_joint(env, "knob/dial", math.radians(50))
    _pot_on_stove(env)
    assert _update(env) == 2 and _ok(env)
    _set_joint(env, "knob/dial", math.radians(40))
    _forward(env)
    assert not _ok(env), "near miss: knob at 40 deg"
    _set_joint(env, "knob/dial", -math.radians(50))
    _pot_on_stove(env, off=(0.09, 0.0, 0.0))
    _forward(env)
    assert not _ok(env), "near miss: 0.09 m off the burner"
    _pot_on_stove(env, tilt=20.0)
    _forward(env)
    assert not _ok(env), "near miss: tilted 20 deg"
    _pot_on_stove(env, spill=True)
    _forward(env)
    assert not _ok(env), "an ingredient fell out"
    _pot_on_stove(env)
    _forward(env)
    assert _ok(env)


def test_cookfood_cooking_before_pouring_fails():
    env = _fresh("CookFood")
    _set_joint(env, "knob/dial", math.radians(50))
    _pot_on_stove(env)
    _pour(env, "bottle", "top", _mouth(env))
    assert _update(env) == 0 and not _ok(env), "only one of the two pours"
    _home(env, "bottle")
    _pour(env, "bottle", "top", _mouth(env))
    _update(env)
    _home(env, "bottle")
    assert _update(env) == 0, "the same vessel twice is not both"


# --- OvenBake --------------------------------------------------------------------------

def _season(env) -> None:
    for jar in ("salt", "pepper"):
        _forward(env)
        _pour(env, jar, "lip", env.view.body_pos("salmon")[0].numpy(), above=0.06)
        _update(env)
        _home(env, jar)


def _salmon_in_oven(env, off=(0.0, 0.0, 0.0)) -> None:
    _forward(env)
    _set_pose(env, "salmon", _box_centre(env, "oven", "cavity", 0.016) + np.asarray(off))


def test_ovenbake_in_order_with_near_misses():
    env = _fresh("OvenBake")
    _forward(env)
    _pour(env, "pepper", "lip", env.view.body_pos("salmon")[0].numpy(), tilt=95.0)
    assert _update(env) == 0 and not env.task.latched(env.view)[0].any(), "tilted 95 deg"
    _home(env, "pepper")
    _salmon_in_oven(env)
    assert _update(env) == 0, "unseasoned salmon in the oven is not a stage"
    _home(env, "salmon")
    _season(env)
    assert _update(env) == 1
    _salmon_in_oven(env, off=(0.0, 0.0, 0.3))
    assert _update(env) == 1, "near miss: above the oven, not in its cavity"
    _salmon_in_oven(env)
    assert _update(env) == 2
    _set_joint(env, "oven/door", math.radians(10))
    assert _update(env) == 2, "near miss: door 10 deg open"
    _set_joint(env, "oven/door", 0.0)
    assert _update(env) == 3
    _set_joint(env, "oven/dial0", math.radians(35))
    assert _update(env) == 3, "near miss: knob 35 deg"
    _set_joint(env, "oven/dial0", math.radians(42))
    assert _update(env) == 4 and _ok(env)


def test_ovenbake_knob_before_door_fails_and_salmon_must_stay():
    env = _fresh("OvenBake")
    _season(env)
    _salmon_in_oven(env)
    _set_joint(env, "oven/dial0", math.radians(45))
    assert _update(env) == 2, "knob turned with the door still open"
    _set_joint(env, "oven/door", 0.0)
    assert _update(env) == 3
    assert _update(env) == 3 and not _ok(env), "the knob must turn after the door closes"
    _set_joint(env, "oven/dial0", 0.0)
    _update(env)
    _set_joint(env, "oven/dial0", math.radians(45))
    assert _update(env) == 4 and _ok(env)
    _home(env, "salmon")
    assert _update(env) == 1 and not _ok(env), "salmon taken out: back to loading it"
    _salmon_in_oven(env)
    assert _update(env) == 2 and bool(torch.all(env.task.latched(env.view))), \
        "the seasoning stays done"


# --- CleanTable ------------------------------------------------------------------------

def _tidy(env, drawer: float = 0.0, lid: float = 0.0, latch: float = math.pi / 2,
          block_in: bool = True, paper_in: bool = True) -> bool:
    _set_joint(env, "cabinet/drawer", drawer)
    _set_joint(env, "bin/hinge", lid)
    _set_joint(env, "bin/latch", latch)
    _forward(env)
    _set_pose(env, "block", _box_centre(env, "cabinet", "inside", 0.026) if block_in
              else _initial(env, "block"))
    _set_pose(env, "paper", _box_centre(env, "bin", "inside", 0.031) if paper_in
              else _initial(env, "paper"))
    _update(env)
    return _ok(env)


def test_cleantable_both_receptacles_at_once():
    env = _fresh("CleanTable")
    assert not _tidy(env, drawer=0.25, lid=env.task.joint_range("bin/hinge")[1], latch=0.0,
                     block_in=False, paper_in=False)
    assert _tidy(env)
    assert float(env.task.state_obs(env.view)[0, -1]) == 1.0
    assert not _tidy(env, drawer=0.01), "near miss: drawer 1 cm open"
    assert not _tidy(env, block_in=False), "near miss: block not in the drawer"
    assert not _tidy(env, lid=math.radians(4)), "near miss: lid 4 deg open"
    assert not _tidy(env, latch=math.radians(70)), "near miss: latch turned 70 deg"
    assert not _tidy(env, paper_in=False), "near miss: paper not in the bin"
    assert _tidy(env)
    _set_joint(env, "cabinet/drawer", 0.1)
    _update(env)
    assert not _ok(env), "the drawer reopened"


def test_cleantable_either_receptacle_first():
    env = _fresh("CleanTable")
    _tidy(env, drawer=0.2)
    assert float(env.task.progress(env.view)[0]) == 0.5 and not _ok(env)
    assert _tidy(env)
    env.reset()
    _tidy(env, latch=0.0)
    assert float(env.task.progress(env.view)[0]) == 0.5 and not _ok(env)
    assert _tidy(env)
