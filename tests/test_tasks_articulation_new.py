"""The "fixate" hold-and-actuate tasks (folder, stapler, utility knife, scissors): a state
that satisfies each paper condition and, for every clause, a near miss that does not."""

import mujoco
import numpy as np
import pytest
import torch
from test_tasks import _fresh

from dexbench.embodiments.hand_geometry import fingertip_thickness
from dexbench.experts import make_expert
from dexbench.experts.adapter import tips_in_palm_frame
from dexbench.experts.hold_actuate import level_row, wedge_depth
from dexbench.sim.backend import INTEGRATION
from dexbench.tasks.registry import make_env


def _with_expert(task: str, embodiment: str | None, num_envs: int, seed: int, **kw):
    """A freshly reset env and its expert, reset too."""
    env = make_env(task, embodiment, num_envs=num_envs, seed=seed, **kw)
    env.reset()
    expert = make_expert(env)
    expert.reset(torch.arange(num_envs))
    return env, expert


def _run_until_solved(env, expert, steps: int) -> torch.Tensor:
    """(N,) which envs the expert solved within `steps` control steps."""
    solved = torch.zeros(env.num_envs, dtype=torch.bool)
    for _ in range(steps):
        _, _, terminated, _, _ = env.step(expert.act())
        solved |= terminated
        if solved.all():
            break
    return solved


def _set_progress(env, joint: str, fraction: float) -> None:
    """Move `joint` `fraction` of the travel reachable from its reset value."""
    lo, hi = env.task.joint_range(joint)
    q0 = env.task.initial_joints[joint]
    sign = 1.0 if hi - q0 >= q0 - lo else -1.0
    adr = env.scene.model.joint(joint).qposadr[0]
    env.sim.field("qpos")[0, adr] = q0 + sign * fraction * max(q0 - lo, hi - q0)


def _ok(env) -> bool:
    env.sim.forward(torch.arange(env.num_envs))
    return bool(env.task.success(env.view)[0])


@pytest.mark.parametrize(("name", "joint", "threshold"), [
    ("OpenFlatFolder", "folder/flap", 0.6),
    ("OpenStapler", "stapler/arm", 0.2),
])
def test_hinge_opens_past_the_threshold_from_its_reset(name, joint, threshold):
    env = _fresh(name)
    assert not _ok(env), "solved at reset"
    _set_progress(env, joint, threshold + 0.02)
    assert _ok(env)
    _set_progress(env, joint, threshold - 0.02)
    assert not _ok(env)


def test_scissors_either_blade_closing_half_way():
    env = _fresh("SqueezeScissors")
    q0 = {j: env.task.initial_joints[j] for j in ("scissors/blade0", "scissors/blade1")}
    assert q0 == {j: env.task.joint_range(j)[1] for j in q0}, "reset wide open"
    for closed in q0:
        for joint in q0:
            _set_progress(env, joint, 0.52 if joint == closed else 0.0)
        assert _ok(env), closed
    for joint in q0:
        _set_progress(env, joint, 0.48)
    assert not _ok(env), "neither blade half closed"


def test_knife_needs_the_blade_out_and_the_knife_lifted_slowly():
    env = _fresh("SlideUtilityKnife")
    model, qpos = env.scene.model, env.sim.field("qpos")
    free = model.joint(env.task.objects["knife"].free_joint)
    z0 = float(qpos[0, free.qposadr[0] + 2])

    def state(blade: float, lift: float, speed: float = 0.0) -> bool:
        _set_progress(env, "knife/blade", blade)
        qpos[0, free.qposadr[0] + 2] = z0 + lift
        env.sim.field("qvel")[0, free.dofadr[0] + 2] = speed
        return _ok(env)

    assert state(0.42, 0.21)
    assert not state(0.38, 0.21), "blade out less than 40%"
    assert not state(0.42, 0.19), "lifted less than 0.2 m"
    assert not state(0.42, 0.21, speed=0.6), "thrown, not held"


def test_hold_actuate_expert_pins_one_ring_and_pushes_the_other():
    env, expert = _with_expert("SqueezeScissors", None, 2, 1)
    solved = _run_until_solved(env, expert, 200)  # the expert needs ~130 of the 480 steps
    assert solved.all()
    assert expert.holder.pressing.all(), "the left hand holds ring 1 down"


def test_knife_arms_keep_their_wrists_apart():
    """On arms the waiting hand's wrist met the pusher's over the knife, and the released
    pusher, hovering there, met the other arm reaching in to pinch (docs/embodiments.md)."""
    env, expert = _with_expert("SlideUtilityKnife", "bimanual_fr3_sharpa", 1, 1000, nthread=1)
    model = env.scene.model
    data = mujoco.MjData(model)
    side = [model.body(model.geom_bodyid[g]).name.split("/")[0] for g in range(model.ngeom)]
    touching = []
    for step in range(260):  # the push, the release and the pinch's descent
        env.step(expert.act())
        if step % 5 == 0:
            mujoco.mj_setState(model, data, env.sim.get_state(INTEGRATION)[0].numpy(),
                               INTEGRATION)
            mujoco.mj_forward(model, data)
            touching += [step for c in data.contact[:data.ncon]
                         if {side[c.geom1], side[c.geom2]} == {"left", "right"}]
    assert expert.started.all(), "the left hand runs its pinch"
    assert not touching, f"the arms touch at steps {sorted(set(touching))}"


def test_stapler_pusher_starts_when_the_holding_wrist_meets_the_table():
    """On arms Shadow's holding forearm meets the table first and rests its finger tips
    ~2.5 cm over the hinge block: the pusher waited on them for the whole episode."""
    env, expert = _with_expert("OpenStapler", "bimanual_fr3_shadow", 1, 0, nthread=1)
    solved = _run_until_solved(env, expert, 300)  # the expert needs ~220 of the 480 steps
    assert expert.stage[0] > 0, "the pusher goes in once the holder has come to rest"
    assert solved.all()


def test_stapler_thick_finger_tips_wedge_under_the_lip():
    """Allegro's 24 mm finger tips don't fit under the stapler's lip (16 mm up): aimed at
    the point they stopped against its face and slid up it, the arm never moved. Aimed
    further in they wedge under its corner. Shadow's 14 mm tips fit under it, Inspire's
    17 mm ones meet its corner steeply enough to lift it: both aim at the point."""
    for hand in ("shadow", "inspire"):
        assert wedge_depth(fingertip_thickness(hand, "right"), 0.008) == 0.0, hand
    env, expert = _with_expert("OpenStapler", "bimanual_floating_allegro", 1, 0, nthread=1)
    assert 0.005 < expert.into[0] < 0.015
    solved = _run_until_solved(env, expert, 300)  # the expert needs ~210 of the 480 steps
    assert solved.all()


def test_folder_flap_lifted_by_a_staggered_finger_row():
    """LEAP's open finger tips step 14 mm along the palm normal from index to ring: with
    its 25 mm tips the row stood 43 mm tall under the flap's 43 mm high edge, the index
    tip's back met the edge from above and pressed the flap shut (0 of 20). Rolled level
    about the fingers, the row fits under it and lifts it."""
    env, expert = _with_expert("OpenFlatFolder", "bimanual_floating_leap", 1, 0, nthread=1)
    assert (expert.chosen == 0).all(), "floating hands reach alike: the right one pushes"
    pusher = expert.experts[0]
    _, _, tips = tips_in_palm_frame(env, pusher._palm, pusher._tips)
    level = np.einsum("nij,nkj->nki", pusher.roll, tips)
    assert np.ptp(tips[0, :, 2]) > 0.01
    assert np.ptp(level[0, :, 2]) < 1e-3, "the row lies in the palm plane"
    assert np.allclose(level_row(np.array([[[0.1, -0.02, 0.0], [0.1, 0.02, 0.0]]])), np.eye(3))
    solved = _run_until_solved(env, expert, 340)  # the expert needs ~310 of the 480 steps
    assert solved.all()
