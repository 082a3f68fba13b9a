"""Embodiment tests: all 48 build and hold still, the arms reach, every hand lifts a cube.

Built from the offline robot models (MENAGERIE_ROOT / DEXBENCH_HANDS_ROOT); skipped when
those are unset. Each scene compiles once per session (`_scene`).
"""

from __future__ import annotations

import functools
import os
import re

import mujoco
import numpy as np
import pytest

from dexbench.assets.objects import add_free_box
from dexbench.embodiments.arms import ARMS
from dexbench.embodiments.builder import (
    HOME_PALM_ROT,
    TABLE_TOP_Z,
    add_embodiment,
    embodiment_names,
    parse_embodiment,
)
from dexbench.embodiments.hand_geometry import hand_geometry, hand_model_spec, palm_face
from dexbench.embodiments.hands import HANDS, SYNERGIES
from dexbench.embodiments.ik import solve_site_pose
from dexbench.embodiments.layout import Embodiment
from dexbench.envs.arena import PhysicsOptions, build_arena

pytestmark = pytest.mark.skipif(
    not (os.environ.get("MENAGERIE_ROOT") and os.environ.get("DEXBENCH_HANDS_ROOT")),
    reason='offline robot models unset: run eval "$(bash <shared>/assets/unpack.sh)"',
)

NAMES = embodiment_names()
ARM_NAMES = [n for n in NAMES if not n.startswith(("bimanual_", "floating_"))]
CUBE_HALF = 0.025
CUBE_MASS = 0.1


@functools.cache
def _scene(name: str, cube: bool = False) -> tuple[mujoco.MjModel, Embodiment]:
    spec = build_arena(PhysicsOptions())
    plan = add_embodiment(spec, name)
    if cube:
        add_free_box(spec, "cube", [CUBE_HALF] * 3, CUBE_MASS)
    model = spec.compile()
    return model, Embodiment.resolve(plan, model)


def _home_data(model: mujoco.MjModel, emb: Embodiment) -> mujoco.MjData:
    data = mujoco.MjData(model)
    for joint, q in emb.home_qpos.items():
        data.qpos[model.joint(joint).qposadr[0]] = q
    data.ctrl[:] = emb.poses["home"]
    mujoco.mj_forward(model, data)
    return data


def _step(model: mujoco.MjModel, data: mujoco.MjData, seconds: float) -> None:
    for _ in range(round(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)


@pytest.mark.parametrize("name", NAMES)
def test_action_layout_is_consistent(name: str) -> None:
    model, emb = _scene(name)
    assert len(emb.actuators) == model.nu == emb.action_dim
    lo, hi = emb.ctrl_range.T
    assert np.isfinite(emb.ctrl_range).all() and (lo < hi).all()
    for pose, vec in emb.poses.items():
        assert vec.shape == (model.nu,)
        assert ((vec >= lo - 1e-9) & (vec <= hi + 1e-9)).all(), f"{pose} outside ctrl range"
    for side, layout in emb.sides.items():
        assert len(layout.fingertip_sites) >= 4, side
        assert all(model.site(s).id >= 0 for s in (layout.palm_site, *layout.fingertip_sites))
    parsed = parse_embodiment(name)
    if parsed.bimanual:
        single = _scene(f"{parsed.mount}_{parsed.hand}")[1].actuators
        assert emb.actuators[: len(single)] == single


@pytest.mark.parametrize("name", NAMES)
def test_holds_home_pose(name: str) -> None:
    """Two seconds at the home action from the home state: nothing falls or drifts."""
    model, emb = _scene(name)
    data = _home_data(model, emb)
    palm0 = {s: data.site(lay.palm_site).xpos.copy() for s, lay in emb.sides.items()}
    hand_joints = [j for lay in emb.sides.values() for j in lay.hand_joints]
    qadr = [model.joint(j).qposadr[0] for j in hand_joints]
    q0 = np.array([emb.home_qpos[j] for j in hand_joints])
    _step(model, data, 2.0)
    assert np.isfinite(data.qpos).all()
    for side, lay in emb.sides.items():
        drift = np.linalg.norm(data.site(lay.palm_site).xpos - palm0[side])
        assert drift < 0.01, f"{side} palm drifted {drift * 100:.1f} cm"
    err = np.abs(data.qpos[qadr] - q0)
    worst = int(err.argmax())
    assert err[worst] < 0.05, f"{hand_joints[worst]} moved {err[worst]:.3f} rad from home"


@pytest.mark.parametrize("hand", list(HANDS))
def test_synergies_differ(hand: str) -> None:
    _, emb = _scene(f"floating_{hand}")
    is_hand = np.array(["/hand/" in a for a in emb.actuators])
    poses = {s: emb.poses[s][is_hand] for s in SYNERGIES}
    for i, a in enumerate(SYNERGIES):
        for b in SYNERGIES[i + 1:]:
            assert np.abs(poses[a] - poses[b]).max() > 0.2, f"{a} and {b} barely differ"


@pytest.mark.parametrize("hand", list(HANDS))
def test_left_hand_frame_mirrors_the_right(hand: str) -> None:
    """The open hand's finger tips (thumb aside) sit where the right hand's do, mirrored
    across the hand frame's y: experts place either hand by one `grasp_offset`. LEAP's
    left model has its palm origin 8 cm from the right's; its tips were 7 cm off."""
    model, emb = _scene(f"bimanual_floating_{hand}")
    data = _home_data(model, emb)
    tips = {}
    for side, lay in emb.sides.items():
        palm = data.site(lay.palm_site)
        local = (data.site_xpos[[model.site(t).id for t in lay.fingertip_sites[1:]]]
                 - palm.xpos) @ palm.xmat.reshape(3, 3)
        tips[side] = local.mean(axis=0)
    gap = np.linalg.norm(tips["left"] - tips["right"] * [1.0, -1.0, 1.0])
    assert gap < 0.005, f"left finger tips {gap * 100:.1f} cm from the right's mirror image"


@pytest.mark.parametrize("hand", list(HANDS))
def test_palm_face_is_where_a_flat_surface_meets_the_open_hand(hand: str) -> None:
    """`palm_face` scans rays; checked here by the collision distance (MuJoCo's own) of a
    plane facing the open palm at the face's height from the palm and fingers (thumb
    aside), and of one across the fingers at its reach from the whole hand: each touches
    within 1.5 mm (the scan's 4 mm grid may miss a rounded tip's peak by a little)."""
    spec, geo = hand_model_spec(HANDS[hand], "right"), hand_geometry(hand, "right")
    face = palm_face(hand, "right")
    spec.option.gravity = [0.0, 0.0, 0.0]
    rot, back = geo.frame_rot, np.diag([1.0, -1.0, -1.0])
    # each plane's z (its normal) points back at the hand: H's -z, and H's -x
    planes = {"face": (face.height * rot[:, 2], rot @ back),
              "reach": (face.reach * rot[:, 0], rot[:, [1, 2, 0]] @ back)}
    for name, (offset, frame) in planes.items():
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, frame.ravel())
        spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.01],
                                contype=0, conaffinity=0, quat=quat.tolist(),
                                pos=(geo.frame_pos + offset).tolist())
    model = spec.compile()
    data = mujoco.MjData(model)
    data.ctrl[:] = geo.synergies["open"]
    for _ in range(2000):
        mujoco.mj_step(model, data)
    sides = HANDS[hand].sides["right"]
    palm = model.body(sides.palm_body).id
    thumb, body = set(), model.body(sides.fingertip_bodies[0]).id
    while body != palm:
        thumb.add(body)
        body = model.body_parentid[body]
    fromto = np.zeros(6)
    for name, skip in (("face", thumb), ("reach", set())):
        plane = model.geom(name).id
        gaps = [mujoco.mj_geomDistance(model, data, plane, g, 1.0, fromto)
                for g in range(model.ngeom) if g != plane
                and (model.geom_contype[g] or model.geom_conaffinity[g])
                and model.geom_bodyid[g] not in skip and _below(model, g, palm)]
        assert abs(min(gaps)) < 0.0015, f"{name} plane {min(gaps) * 1000:.1f} mm from the hand"


def _below(model: mujoco.MjModel, geom: int, palm: int) -> bool:
    """Whether geom `geom` is on body `palm` or a body below it (a finger)."""
    body = model.geom_bodyid[geom]
    while body not in (palm, 0):
        body = model.body_parentid[body]
    return body == palm


# The thumb's actuators of each hand, by name: `hook` must find exactly these itself.
THUMB_ACTUATORS = {"shadow": r"A_TH", "allegro": r"/tha\d", "leap": r"/th_",
                   "sharpa": r"thumb", "inspire": r"thumb", "wuji": r"finger1_"}


@pytest.mark.parametrize("hand", [h for h in HANDS if "hook" not in HANDS[h].synergies])
def test_hook_curls_the_fingers_and_leaves_the_thumb_open(hand: str) -> None:
    """The derived `hook` (a hand declaring its own keeps that one)."""
    _, emb = _scene(f"floating_{hand}")
    is_hand = np.array(["/hand/" in a for a in emb.actuators])
    thumb = np.array([re.search(THUMB_ACTUATORS[hand], a) is not None for a in emb.actuators])
    assert thumb.any()
    hook, opened, power = (emb.poses[s] for s in ("hook", "open", "power"))
    np.testing.assert_array_equal(hook[is_hand & thumb], opened[is_hand & thumb])
    np.testing.assert_array_equal(hook[is_hand & ~thumb], power[is_hand & ~thumb])


@pytest.mark.parametrize("name", ARM_NAMES)
def test_arm_reaches_above_table_centre(name: str) -> None:
    """Moving only the arm, the index fingertip reaches 10 cm above the table centre,
    touching nothing on the way there (the IK solution is collision-free; contacts the
    open hand already has at home, such as a thumb resting on its palm, are its own)."""
    model, emb = _scene(name)
    data = _home_data(model, emb)
    at_home = _touching(model, data)
    side = emb.sides["right"]
    target = np.array([0.0, 0.0, TABLE_TOP_Z + 0.1])
    tip = side.fingertip_sites[1]
    solve_site_pose(model, data, tip, list(side.mount_joints), target, iterations=500)
    mujoco.mj_forward(model, data)
    assert np.linalg.norm(data.site(tip).xpos - target) < 0.01
    touching = _touching(model, data) - at_home
    assert not touching, f"the reaching arm collides: {sorted(touching)}"


def _touching(model: mujoco.MjModel, data: mujoco.MjData) -> set[tuple[str, str]]:
    """Pairs of bodies in contact."""
    return {tuple(model.body(model.geom_bodyid[g]).name for g in (c.geom1, c.geom2))
            for c in data.contact[: data.ncon]}


def _place_cube(model: mujoco.MjModel, data: mujoco.MjData, hand: str) -> float:
    """Put the cube on the table where the home palm's grasp offset points; return the
    palm height that grasps it (the palm only moves vertically)."""
    offset = HOME_PALM_ROT @ np.asarray(HANDS[hand].grasp_offset)
    cube = data.site("right/hand/palm").xpos + offset
    cube[2] = TABLE_TOP_Z + CUBE_HALF
    adr = model.joint("cube/free").qposadr[0]
    data.qpos[adr : adr + 7] = [*cube, 1, 0, 0, 0]
    mujoco.mj_forward(model, data)
    return float(cube[2] - offset[2])


def _grasp_and_lift(model, data, emb, grasp_z, mount_ctrl) -> tuple[float, float]:
    """Lower the open hand to `grasp_z`, close to `power` over 0.5 s, wait 1 s, raise the
    palm 15 cm over 1 s and hold 1 s, at the 60 Hz control rate.

    `mount_ctrl(z)` gives (actuator indices, targets) that put the palm at height z.
    Returns (cube lift, distance from the cube to the mean fingertip).
    """
    cube0 = data.body("cube").xpos.copy()
    z_home = data.site("right/hand/palm").xpos[2]
    open_, power = emb.poses["open"], emb.poses["power"]
    hand = np.array(["/hand/" in a for a in emb.actuators])
    phases = (  # (seconds, palm height from, to, closure from, to)
        (1.0, z_home, grasp_z, 0, 0), (0.2, grasp_z, grasp_z, 0, 0),
        (0.5, grasp_z, grasp_z, 0, 1), (1.0, grasp_z, grasp_z, 1, 1),
        (1.0, grasp_z, grasp_z + 0.15, 1, 1), (1.0, grasp_z + 0.15, grasp_z + 0.15, 1, 1),
    )
    decimation = PhysicsOptions().decimation
    ctrl = open_.copy()
    for seconds, z0, z1, c0, c1 in phases:
        n = round(seconds / (decimation * model.opt.timestep))
        for k in range(1, n + 1):
            a = k / n
            closure = c0 + (c1 - c0) * a
            ctrl[hand] = (open_ + closure * (power - open_))[hand]
            idx, targets = mount_ctrl(z0 + (z1 - z0) * a)
            ctrl[idx] = targets
            data.ctrl[:] = ctrl
            for _ in range(decimation):
                mujoco.mj_step(model, data)
    tips = np.mean([data.site(s).xpos for s in emb.sides["right"].fingertip_sites], axis=0)
    cube = data.body("cube").xpos
    return float(cube[2] - cube0[2]), float(np.linalg.norm(tips - cube))


def _check_lift(lift: float, spread: float) -> None:
    assert lift >= 0.10, f"cube rose only {lift * 100:.1f} cm"
    assert spread < 0.06, f"cube is {spread * 100:.1f} cm from the mean fingertip"


@pytest.mark.parametrize("hand", list(HANDS))
def test_floating_hand_lifts_cube(hand: str) -> None:
    """Top-down power grasp of a 0.1 kg, 5 cm cube at the hand's `grasp_offset`."""
    model, emb = _scene(f"floating_{hand}", cube=True)
    data = _home_data(model, emb)
    grasp_z = _place_cube(model, data, hand)
    wrist_z = [emb.actuators.index("right/wrist/z")]
    z_home = emb.sides["right"].home_palm_pos[2]
    _check_lift(*_grasp_and_lift(model, data, emb, grasp_z, lambda z: (wrist_z, z - z_home)))


@pytest.mark.parametrize("name", ["xarm7_shadow", "ur10e_shadow", "fr3_shadow"])
def test_arm_hand_lifts_cube(name: str) -> None:
    """The same grasp on an arm: IK on the arm joints keeps the palm level and moves it."""
    model, emb = _scene(name, cube=True)
    data = _home_data(model, emb)
    grasp_z = _place_cube(model, data, "shadow")
    side = emb.sides["right"]
    arm = [i for i, a in enumerate(emb.actuators) if a.startswith("right/arm/")]
    joints = [model.joint(model.actuator_trnid[i, 0]).name for i in arm]
    palm_xy = data.site(side.palm_site).xpos[:2].copy()
    scratch = mujoco.MjData(model)
    scratch.qpos[:] = data.qpos

    def arm_ctrl(z: float):
        target = np.array([*palm_xy, z])
        q, err = solve_site_pose(model, scratch, side.palm_site, joints, target,
                                 HOME_PALM_ROT, iterations=50)
        assert err < 2e-3, f"arm IK misses the palm target by {err:.4f}"
        return arm, q

    _check_lift(*_grasp_and_lift(model, data, emb, grasp_z, arm_ctrl))


@pytest.mark.parametrize("name", [n for n in ARM_NAMES
                                  if ARMS[parse_embodiment(n).mount].damping_ratio])
def test_arm_palm_keeps_up_with_a_moving_target(name: str) -> None:
    """An arm with a `damping_ratio` has servos damped that much at home, and its palm
    follows a target sliding 0.3 m/s across the table within 1.5 cm (the FR3 model's own
    kv = kp/10 lagged 3 cm: the experts took their plans for blocked)."""
    model, emb = _scene(name)
    data = _home_data(model, emb)
    side = emb.sides["right"]
    arm = [i for i, a in enumerate(emb.actuators) if a.startswith("right/arm/")]
    joints = [model.joint(model.actuator_trnid[i, 0]).name for i in arm]
    inertia = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, inertia)
    wanted = ARMS[parse_embodiment(name).mount].damping_ratio
    for i, joint in zip(arm, joints, strict=True):
        dof = model.joint(joint).dofadr[0]
        kv = model.dof_damping[dof] - model.actuator_biasprm[i, 2]
        ratio = kv / (2 * np.sqrt(model.actuator_gainprm[i, 0] * inertia[dof, dof]))
        assert ratio == pytest.approx(wanted, rel=0.2), f"{joint} damping ratio {ratio:.2f}"
    scratch = mujoco.MjData(model)
    scratch.qpos[:] = data.qpos
    start = data.site(side.palm_site).xpos.copy()
    decimation = PhysicsOptions().decimation
    dt = decimation * model.opt.timestep
    lag = []
    for k in range(1, round(0.4 / dt) + 1):
        target = start + [0.0, 0.3 * k * dt, 0.0]
        q, _ = solve_site_pose(model, scratch, side.palm_site, joints, target, HOME_PALM_ROT,
                               iterations=20)
        data.ctrl[arm] = q
        for _ in range(decimation):
            mujoco.mj_step(model, data)
        lag.append(np.linalg.norm(data.site(side.palm_site).xpos - target))
    worst = max(lag[len(lag) // 2:])
    assert worst < 0.015, f"palm lags its target by {worst * 100:.1f} cm"
