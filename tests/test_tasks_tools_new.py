"""GraspPan, RetrieveCup and FunctionalHammerStrike: for each, a state that satisfies the
paper's success condition and, per clause, a near miss that does not."""

import numpy as np
import torch
from test_tasks import _forward, _fresh, _ok, _place_point, _point, _quat_about, _set_joint

from dexbench.experts.adapter import ActionAdapter
from dexbench.experts.grasp import squeezed
from dexbench.tasks.registry import make_env


def _touch(env, point) -> None:
    """Move the floating right hand so its last collision geom's centre is at `point`."""
    tip = env.view.hand_geom_pos()[0, -1].numpy()
    for k, axis in enumerate("xyz"):
        joint = f"right/wrist/{axis}"
        _set_joint(env, joint, float(env.view.joint_pos(joint)[0]) + float((point - tip)[k]))
    _forward(env)


def test_grasp_pan_each_condition():
    env = _fresh("GraspPan")
    target = _point(env, "stove", "target")
    _place_point(env, "pan", "centre", target + [0.015, 0.0, 0.002])
    assert _ok(env)
    _place_point(env, "pan", "centre", target + [0.03, 0.0, 0.002])
    assert not _ok(env), "centre too far from the burner"
    _place_point(env, "pan", "centre", target + [0.0, 0.0, 0.03], _quat_about("y", 12.0))
    assert not _ok(env), "not flat"
    _place_point(env, "pan", "centre", target + [0.0, 0.0, 0.002])
    assert _ok(env)
    _touch(env, _point(env, "pan", "centre") + [0.0, 0.0, 0.012])
    assert not _ok(env), "a hand touches the cooking surface"


def test_retrieve_cup_each_condition():
    env = _fresh("RetrieveCup")
    goal = env.view.goal[0, :3].numpy()
    assert not _ok(env), "still in the rack"
    _place_point(env, "cup", "bottom", goal + [0.03, 0.0, 0.0])
    assert _ok(env)
    _place_point(env, "cup", "bottom", goal + [0.05, 0.0, 0.0])
    assert not _ok(env), "too far from the goal"
    _place_point(env, "cup", "bottom", goal + [0.0, 0.0, 0.01], _quat_about("x", 20.0))
    assert not _ok(env), "not upright"


def test_retrieve_cup_starts_in_the_rack_slot():
    env = make_env("RetrieveCup", num_envs=3, seed=5, nthread=1)
    env.reset()
    task = env.task
    slot = task.point(env.view, "rack", "slot")
    assert torch.allclose(task.point(env.view, "cup", "bottom"), slot, atol=1e-6)
    goal = env.view.goal[:, :3]
    assert ((goal[:, 1] >= -0.40) & (goal[:, 1] <= -0.25)).all()


def test_hammer_strike_needs_the_nail_driven_and_never_touched_by_a_hand():
    env = _fresh("FunctionalHammerStrike")
    task = env.task
    _set_joint(env, "board/nail", -0.061)
    assert _ok(env)
    _set_joint(env, "board/nail", -0.059)
    assert not _ok(env), "not driven 0.06 m"
    # A finger on the nail head: the episode's memory keeps it, even once the hand is off.
    head = _point(env, "board", "nail_head")
    _touch(env, head + [0.0, 0.0, 0.004])
    task.update(env.view)
    assert env.view.memory[0, 0] == 1.0
    _set_joint(env, "board/nail", -0.061)
    _touch(env, head + [0.0, -0.3, 0.3])
    task.update(env.view)
    assert not _ok(env), "the hand touched the nail head"
    env.reset()
    assert env.view.memory[0, 0] == 0.0


def test_hammer_starts_standing_on_its_stand():
    env = make_env("FunctionalHammerStrike", num_envs=3, seed=2, nthread=1)
    env.reset()
    hammer = env.view.body_pos("hammer").numpy()
    for _ in range(30):
        env.step(env.home_action.repeat(3, 1))
    assert np.abs(env.view.body_pos("hammer").numpy() - hammer).max() < 0.003
    assert ((env.view.body_pos("board")[:, 1] >= 0.2) & (env.view.body_pos("board")[:, 1]
                                                         <= 0.3)).all()


def test_a_squeezed_grasp_closes_further_than_its_synergy_within_range():
    env = _fresh("FunctionalHammerStrike")
    adapter = ActionAdapter(env)
    assert squeezed(adapter, env, "power", 1.0) == "power"
    opened, closed = adapter.pose("open"), adapter.pose("power")
    tight = adapter.pose(squeezed(adapter, env, "power", 2.0))
    lo, hi = env.embodiment.ctrl_range.T
    assert ((tight >= lo) & (tight <= hi)).all()
    assert (np.abs(tight - opened) >= np.abs(closed - opened) - 1e-9).all()
    assert (np.abs(tight - opened) > np.abs(closed - opened) + 1e-6).any()
