"""Scripted experts: the action adapter reaches commanded palm poses on any mount, and
the task scripts succeed (closed loop, a few parallel envs)."""

from types import SimpleNamespace

import numpy as np
import pytest
import torch

from dexbench.assets.objects import T_SHAPE_RECTS
from dexbench.eval.seeds import eval_keys
from dexbench.experts import make_expert
from dexbench.experts.adapter import ActionAdapter, HandCommand
from dexbench.experts.motion import palm_down, turned
from dexbench.experts.push import inside_rects, outline
from dexbench.tasks.plans import body_yaw
from dexbench.tasks.registry import TASKS, make_env


@pytest.mark.parametrize("embodiment", ["floating_allegro", "xarm7_shadow", "fr3_wuji"])
def test_adapter_puts_the_palm_where_commanded(embodiment):
    env = make_env("PickCube", embodiment, num_envs=2, seed=1)
    env.reset()
    adapter = ActionAdapter(env)
    adapter.reset(np.arange(2))
    target = np.array([[-0.1, 0.1, 0.75], [0.05, -0.1, 0.72]])
    rot = palm_down(np.array([0.3, -0.5]))
    command = HandCommand(target, rot, np.array([0.0, 1.0]))
    for _ in range(90):
        env.step(adapter.actions({"right": command}))
    site = env.scene.model.site(env.embodiment.sides["right"].palm_site).id
    pos = env.sim.field("site_xpos")[:, site].numpy()
    mat = env.sim.field("site_xmat")[:, site].numpy().reshape(-1, 3, 3)
    # Millimetre tracking on every mount (the xArm7's wrist chattered ~0.2 rad off its
    # target before its joints got an armature floor: `ArmSpec.armature`).
    assert np.linalg.norm(pos - target, axis=1).max() < 0.003
    cos = (np.einsum("nij,nij->n", mat, rot) - 1) / 2
    assert np.arccos(np.clip(cos, -1, 1)).max() < 0.02
    hand = [i for i, a in enumerate(env.embodiment.actuators) if "/hand/" in a]
    ctrl = env.sim.field("ctrl").numpy()
    np.testing.assert_allclose(ctrl[0, hand], env.embodiment.poses["open"][hand])
    np.testing.assert_allclose(ctrl[1, hand], env.embodiment.poses["power"][hand])


@pytest.mark.parametrize(("task", "embodiment"), [
    ("PickCube", "floating_shadow"), ("PushButton", "floating_shadow"),
    ("TurnOnSwitch", "floating_shadow"), ("OpenFaucet", "floating_shadow"),
    ("OpenDrawer", "floating_shadow"), ("StackCube", "floating_shadow"),
    ("BimanualLiftTray", "bimanual_floating_shadow")])
def test_expert_solves_task_on_floating_shadow(task, embodiment):
    solved = _solved(task, embodiment, seed=3, enough=3)
    assert solved >= 3, f"{task}: expert solved {solved}/4"


# MakeCoffee's expert succeeds in about half its episodes since its predicate became
# honest (docs/experts.md); these 4 episodes gave 3 when written and give 2 with the
# dependencies as pinned now (numpy 2.2.6; it was unpinned before).
@pytest.mark.parametrize(("task", "seed", "minimum"), [
    ("FunctionalPourMug", 0, 3), ("MakeCoffee", 1, 2), ("GraspTwoItems", 0, 1),
    ("CookFood", 0, 3)])
def test_task_specific_expert_solves_on_floating_shadow(task, seed, minimum):
    solved = _solved(task, "floating_shadow", seed=seed, enough=minimum)
    assert solved >= minimum, f"{task}: expert solved {solved}/4"


@pytest.mark.parametrize(("task", "minimum"), [("SlideUtilityKnife", 3), ("InsertPen", 2)])
def test_pinch_experts_solve_on_the_default_embodiment(task, minimum):
    """The thin-object tip pinch (`PinchPlan`): the knife's left hand lifts it by the
    handle after the right slid the blade out; the right hand picks the pen off the table."""
    solved = _solved(task, None, seed=0, enough=minimum)
    assert solved >= minimum, f"{task}: expert solved {solved}/4"


@pytest.mark.parametrize(("embodiment", "seed"), [("ur10e_leap", 3), ("xarm7_leap", 0)])
def test_pick_expert_on_arm_mounted_leap(embodiment, seed):
    solved = _solved("PickCube", embodiment, seed=seed, enough=3)
    assert solved >= 3, f"PickCube on {embodiment}: expert solved {solved}/4"


def test_wuji_holds_the_pan_handle_on_its_own_diagonal():
    """`HandSpec.bar_yaw`: square across the handle (0) the Wuji hand solves none of these
    four GraspPan episodes; turned -0.7 rad it solves all four."""
    assert _solved("GraspPan", "floating_wuji", seed=1, enough=4) == 4


def test_sharpa_takes_the_cup_by_its_rim_at_its_own_place():
    """`HandSpec.shifts["rim"]`: at the Shadow hand's place on the rim the Sharpa hand
    retrieves none of these four cups; 3 cm back along its fingers, all four."""
    assert _solved("RetrieveCup", "floating_sharpa", seed=1, enough=4) == 4


def test_leap_takes_the_hammer_nearer_its_wrist():
    """`HandSpec.shifts["tool"]`: at the Shadow hand's place on the handle the closing
    LEAP fingers knock the standing hammer over and none of these four nails is driven;
    2.5 cm towards the wrist, all four."""
    keys = eval_keys(0, [0, 2, 4, 6])
    assert _solved("FunctionalHammerStrike", "floating_leap", seed=0, enough=4, keys=keys) == 4


def test_leap_holds_the_cup_round_its_body_nearer_its_palm():
    """`HandSpec.shifts["vessel"]`: 1 cm further out along the LEAP fingers the cup of
    these four episodes is not lifted and poured (0 of 4); at the palm's side of that,
    all four."""
    keys = eval_keys(0, [0, 2, 3, 5])
    assert _solved("GraspCup", "floating_leap", seed=0, enough=4, keys=keys) == 4


def test_inspire_takes_the_cup_rim_off_its_thumb_on_the_fr3():
    """`HandSpec.shifts["rim"]`: at the Shadow hand's place on the rim the FR3's Inspire
    hand sets these four cups down too tilted to stand (0 of 4); 1.5 cm along hand -y,
    all four stand on the goal."""
    keys = eval_keys(0, [0, 1, 3, 7])
    assert _solved("RetrieveCup", "fr3_inspire", seed=0, enough=4, keys=keys) == 4


def test_wuji_holds_the_hammer_further_from_its_palm_on_the_fr3():
    """`HandSpec.shifts["tool"]`: 1.2 cm off the palm the FR3's Wuji hand drives none of
    these four nails; 2.7 cm off, all four."""
    keys = eval_keys(0, [0, 4, 5, 6])
    assert _solved("FunctionalHammerStrike", "fr3_wuji", seed=0, enough=4, keys=keys) == 4


def test_wuji_hooks_the_kettle_handle_at_its_own_place():
    """`HandSpec.shifts["handle"]`: at the Shadow hand's place on the kettle's handle the
    Wuji hand pours none of these four (0 of 4); 1 cm along hand -y, all four."""
    keys = eval_keys(0, [0, 1, 3, 9])
    assert _solved("GraspKettle", "floating_wuji", seed=0, enough=4, keys=keys) == 4


def test_sharpa_hangs_the_pen_from_its_tips_with_the_long_part_back():
    """`HandSpec.hang_back`: pinched with the pen's long part out past its fingertips, the
    Sharpa hand loses these four pens in the tip-down turn (0 of 4 inserted); with it
    back towards the wrist, all four go in."""
    keys = eval_keys(0, [3, 4, 7, 8])
    assert _solved("InsertPen", "floating_sharpa", seed=0, enough=4, keys=keys) == 4


def test_push_expert_leans_the_fingers_where_the_arm_cannot_hang_them():
    """PushT on the FR3: with the fingers straight down the arm missed the far pushes by
    ~10 cm; leaning them out where it cannot reach (`LEANS`), these 4 are solved (2 of
    them straight down). Over episodes 0-11 the leans no longer add up since the push
    steers the finger's front (5 solved with them, 6 without): they matter episode by
    episode."""
    keys = eval_keys(0, [0, 2, 4, 8])
    solved = _solved("PushT", "fr3_shadow", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"PushT on fr3_shadow: expert solved {solved}/4"


def test_strike_presses_deeper_where_the_wrist_is_soft():
    """FunctionalHammerStrike on the UR10e: presses of the floating wrist's depth drove the
    nail ~4 mm each and none of these 4 was home in time; deepened after each slow press
    (`strike.DEEPER`), 3 of 4."""
    keys = eval_keys(0, [0, 1, 2, 3])
    solved = _solved("FunctionalHammerStrike", "ur10e_shadow", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"HammerStrike on ur10e_shadow: expert solved {solved}/4"


def test_strike_comes_down_to_the_nail_from_above():
    """FunctionalHammerStrike on the UR10e: carried straight at the hover point, the
    lagging arm brought the hand level with the nail head beside it and touched it in all
    of these 4; with the hover point raised while the face is off to the side
    (`strike.CONE`), 4 of 4."""
    keys = eval_keys(0, [4, 6, 7, 8])
    solved = _solved("FunctionalHammerStrike", "ur10e_shadow", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"HammerStrike on ur10e_shadow: expert solved {solved}/4"


def test_wuji_holds_the_hammer_where_its_own_grip_keeps_it():
    """FunctionalHammerStrike, floating Wuji: at the Shadow hand's grasp the lifted head
    tipped the hammer out of the grip in all of these 4; at Wuji's own (`shifts["tool"]`),
    4 of 4."""
    keys = eval_keys(0, [9, 13, 14, 15])
    solved = _solved("FunctionalHammerStrike", "floating_wuji", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"HammerStrike on floating_wuji: expert solved {solved}/4"


def test_lid_lifted_off_soft_finger_tips():
    """OpenLaptop's pads go past the lid's edge (`TurnPlan.under`): resting on the tips,
    Wuji's soft fingers bent under the lid and lifted it in none of these 4."""
    keys = eval_keys(0, [0, 3, 4, 5])
    solved = _solved("OpenLaptop", "bimanual_floating_wuji", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"OpenLaptop on Wuji: expert solved {solved}/4"


def test_lid_rests_near_soft_fingers_knuckles_on_an_arm():
    """OpenLaptop, Wuji hands on FR3s: with the pads 12 mm past the lid's edge the soft
    fingers bent under it and it stalled at ~25 degrees in all of these 4; 3 cm past,
    4 of 4."""
    keys = eval_keys(0, [0, 3, 4, 5])
    solved = _solved("OpenLaptop", "bimanual_fr3_wuji", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"OpenLaptop on fr3_wuji: expert solved {solved}/4"


def test_lid_reached_over_the_top():
    """OpenLaptop on the UR10e with LEAP hands: going straight from the arm's start to the
    low hover in front of the lid, the tilted fingers swept across the lid and pressed it
    shut in all of these 4; over the top (`motion.via_travel`), 4 of 4."""
    keys = eval_keys(0, [0, 4, 7, 8])
    solved = _solved("OpenLaptop", "bimanual_ur10e_leap", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"OpenLaptop on ur10e_leap: expert solved {solved}/4"


def test_pressing_palms_centre_their_faces_on_the_box():
    """BimanualLiftCarton with LEAP hands on FR3s: pressing at the hand's `grasp_offset`
    (a held cube's place, 5.5 cm to the side of LEAP's fingers) the two palms met the box
    off its middle and it swung about their line as it rose, in all of these 4; with the
    middle of each pressing face on the grip point (`palm_face`), 4 of 4."""
    keys = eval_keys(0, [1, 2, 13, 15])
    solved = _solved("BimanualLiftCarton", "bimanual_fr3_leap", seed=0, enough=3, keys=keys)
    assert solved >= 3, f"BimanualLiftCarton on fr3_leap: expert solved {solved}/4"


def test_pressing_palms_go_equally_deep_into_the_box():
    """BimanualLiftCarton with floating Sharpa hands: placed by the palm's site, Sharpa's
    face (further back than the plan's hand assumed) went 2.4 cm into the box, too little
    to carry it (0 of 20); each face pushed 5 cm in (`palm_face`), 4 of 4."""
    solved = _solved("BimanualLiftCarton", "bimanual_floating_sharpa", seed=0, enough=3,
                     keys=eval_keys(0, [0, 1, 2, 3]))
    assert solved >= 3, f"BimanualLiftCarton on floating_sharpa: expert solved {solved}/4"


def test_pressing_hands_turn_where_the_arm_cannot_hang_them_straight():
    """BimanualLiftCarton with Shadow hands on UR10es: the wrist cannot hang the fingers
    straight down beside the box (orientation residual ~0.4 rad), the palms missed their
    faces' places and the box stayed (0.10 over 20, these 4 all failed); each hand now
    takes the least turn about its palm normal that its arm reaches
    (`TwoHandLiftExpert._choose_rolls`; 0.50 over 20)."""
    solved = _solved("BimanualLiftCarton", "bimanual_ur10e_shadow", seed=0, enough=3,
                     keys=eval_keys(0, [1, 6, 7, 9]))
    assert solved >= 3, f"BimanualLiftCarton on ur10e_shadow: expert solved {solved}/4"


def test_pressing_hands_turn_as_far_as_the_arm_gets_there():
    """BimanualLiftCarton with Shadow hands on UR10es: the turn a pressing hand takes was
    scored on its press poses alone, each solved from the arm's joints in one go; the left
    arm, following its way there step by step, ended 21 cm and 31 deg off the grip (these
    4 failed; 0.45 over 20). Scored with the way in from the hand's pose
    (`motion.way_poses`), the turn is one the arm gets to (0.90 over 20)."""
    solved = _solved("BimanualLiftCarton", "bimanual_ur10e_shadow", seed=0, enough=3,
                     keys=eval_keys(0, [0, 3, 4, 5]))
    assert solved >= 3, f"BimanualLiftCarton on ur10e_shadow: expert solved {solved}/4"


def test_holding_fingers_keep_off_the_moving_blade():
    """SqueezeScissors with floating Allegro hands: the holding hand pressed ring 1 with
    its fingers' mean, which put a tip of its wide-spread fingers on ring 0's blade and
    held the scissors open (0 of 20); pressing with the tip that keeps the others off it
    (`PressPlan.keep_off`), 4 of 4."""
    solved = _solved("SqueezeScissors", "bimanual_floating_allegro", seed=0, enough=3,
                     keys=eval_keys(0, [0, 1, 2, 3]))
    assert solved >= 3, f"SqueezeScissors on floating_allegro: expert solved {solved}/4"


def test_the_hand_whose_arm_reaches_the_flap_lifts_it():
    """OpenFlatFolder with Shadow hands on FR3s: the right hand alone reached across for
    a folder on the left half of the table, its elbow nearly straight, and slid off the
    flap short of the task's 60% (these 4 failed, 9 of 20 passed); each episode now
    pushes with the hand whose arm reaches the push (`EitherHandExpert`; 18 of 20)."""
    solved = _solved("OpenFlatFolder", "bimanual_fr3_shadow", seed=0, enough=3,
                     keys=eval_keys(0, [1, 2, 6, 9]))
    assert solved >= 3, f"OpenFlatFolder on fr3_shadow: expert solved {solved}/4"


def _solved(task: str, embodiment: str | None, seed: int, enough: int,
            keys: np.ndarray | None = None) -> int:
    """Episodes of 4 envs the task's expert solves, stopping once `enough` are (`keys`:
    the episodes' reset keys; default: the env's own)."""
    env = make_env(task, embodiment, num_envs=4, seed=seed)
    if keys is None:
        env.reset()
    else:
        env.reset_to(np.arange(4), keys)
    expert = make_expert(env)
    expert.reset(torch.arange(4))
    solved = torch.zeros(4, dtype=torch.bool)
    for _ in range(env.episode_steps):
        _, _, terminated, _, _ = env.step(expert.act())
        solved |= terminated
        if solved.sum() >= enough:
            break
    return int(solved.sum())


def test_turned_is_the_rotation_about_each_axis():
    axes = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    rot = turned(axes, np.array([np.pi / 2, np.pi]))
    np.testing.assert_allclose(rot[0] @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(rot[1] @ [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(rot @ axes[..., None], axes[..., None], atol=1e-12)


def test_peg_expert_inserts_the_peg():
    solved = _solved("InsertPeg", None, seed=INSERT_SEED, enough=2)
    assert solved >= 2, f"InsertPeg: expert solved {solved}/4"


INSERT_SEED = 2  # over many seeds ~80% succeed (collect: 48/60); this seed solves 3/4


def test_every_task_has_an_expert_and_an_unknown_one_names_those_that_exist():
    for task in TASKS:
        assert make_expert(make_env(task, num_envs=1, nthread=1)) is not None
    unknown = SimpleNamespace(task=SimpleNamespace(name="NoSuchTask"))
    with pytest.raises(ValueError, match=r"experts exist for .*PickCube"):
        make_expert(unknown)


def test_push_expert_pushes_the_t_onto_its_goal():
    solved = _solved("PushT", "floating_shadow", seed=PUSHT_SEED, enough=2)
    assert solved >= 2, f"PushT: expert solved {solved}/4"


PUSHT_SEED = 2  # over many seeds ~88% succeed (collect: 50/57); this seed solves 4/4


def test_push_candidates_sit_on_the_outline_and_push_inwards():
    rects = np.array(T_SHAPE_RECTS)
    points, pushes = outline(rects)
    assert len(points) > 40
    assert not inside_rects(points - 1e-3 * pushes, rects, 0.0).any()  # just outside
    assert inside_rects(points + 1e-3 * pushes, rects, 0.0).all()  # just inside


def test_carrying_to_the_goal_leaves_the_tasks_goal_where_it_was_sampled():
    """The grasp expert raises its carry target over clutter; that must be its own copy:
    `task_goal` reads the task's goal, which the success check and the goal observation
    use (it once moved the goal up mid-episode)."""
    env = make_env("RelocateSphere", num_envs=2, seed=0, nthread=1)
    env.reset()
    expert = make_expert(env)
    expert.reset(torch.arange(2))
    sampled = env.view.goal.clone()
    for _ in range(300):
        env.step(expert.act())
    assert torch.equal(env.view.goal, sampled)


def test_arm_turns_the_mug_grasp_only_where_the_handle_stays_clear():
    """`PourPlan.round_body` with a `HandleBetween` grasp yaw: on an arm the mug's body
    grasp may turn about its axis like a can's, to where the arm reaches best, but never
    so far that the handle comes between the palm and the mug (the mug's range leaves it
    at least ~40 deg off that line). Without
    the handle filter, fr3_wuji's episodes 1 and 6 here turned the handle to 15 deg of it."""
    env = make_env("FunctionalPourMug", "fr3_wuji", num_envs=8, seed=0, nthread=1)
    env.reset_to(torch.arange(8), eval_keys(0, list(range(8))))
    expert = make_expert(env)
    expert.reset(torch.arange(8))
    for _ in range(3):  # the grasp is planned (and turned) on the approach's second step
        env.step(expert.act())
    held = expert._held_rot
    yaw = body_yaw(env.view.body_quat("mug").cpu().numpy())  # the handle along mug +x
    handle = np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
    to_palm = -held[:, :2, 2] / np.linalg.norm(held[:, :2, 2], axis=1, keepdims=True)
    off = np.degrees(np.arccos(np.clip((handle * to_palm).sum(axis=1), -1.0, 1.0)))
    assert off.min() > 40.0, off
    fingers = np.arctan2(held[:, 1, 0], held[:, 0, 0])
    turn = (fingers - yaw - expert.plan.grasp.yaw_offset(env) + np.pi) % (2 * np.pi) - np.pi
    assert (np.abs(turn) > 0.1).any(), "no grasp turned: the test no longer checks the filter"
