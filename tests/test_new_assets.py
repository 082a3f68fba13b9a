"""Assets of the 14 new baseline tasks: consistent metadata, stable at rest, mechanisms
that move within their ranges, containers that hold what is put in them."""

import math

import mujoco
import numpy as np
import pytest
from test_objects import _check_metadata

from dexbench.assets import cutters, kitchen, objects, office, procedural, ramps, tools, vessels
from dexbench.assets.objects import new_spec
from dexbench.envs.arena import PhysicsOptions, apply_options

FREE = {  # builder, mass (kg)
    "carton": (lambda s: kitchen.add_carton(s, "carton"), 0.8),
    "bleach": (lambda s: vessels.add_bleach_bottle(s, "bleach"), 0.4),
    "kettle": (lambda s: vessels.add_kettle(s, "kettle"), 0.6),
    "can": (lambda s: vessels.add_can(s, "can"), 0.12),
    "pan": (lambda s: kitchen.add_pan(s, "pan"), 0.3),
    "folder": (lambda s: office.add_flat_folder(s, "folder"), 0.18),
    "stapler": (lambda s: office.add_stapler(s, "stapler"), 0.33),
    "pen": (lambda s: office.add_pen(s, "pen"), 0.02),
    "knife": (lambda s: cutters.add_utility_knife(s, "knife"), 0.11),
    "scissors": (lambda s: cutters.add_scissors(s, "scissors"), 0.08),
    "hammer": (lambda s: tools.add_hammer(s, "hammer"), 0.32),
}
FIXED = {
    "stove": lambda s: kitchen.add_stove(s, "stove"),
    "rack": lambda s: kitchen.add_cup_rack(s, "rack"),
    "holder": lambda s: office.add_pen_holder(s, "holder"),
    "stand": lambda s: tools.add_hammer_stand(s, "stand"),
    "board": lambda s: tools.add_nail_board(s, "board"),
    "ramp": lambda s: ramps.add_ramp(s, "ramp"),
    "posts": lambda s: ramps.add_obstacle_pair(s, "posts"),
}
# Joint values the objects rest at in the test, like a task's reset (folder near-closed,
# stapler ajar, scissors wide open, blade half out): friction must hold them there.
AJAR = {"folder/flap": math.radians(10), "stapler/arm": math.radians(30),
        "scissors/blade0": math.radians(20), "scissors/blade1": math.radians(20),
        "knife/blade": 0.02}
ZONED = {"bleach": FREE["bleach"][0], "kettle": FREE["kettle"][0], "can": FREE["can"][0],
         "pan": FREE["pan"][0], "board": FIXED["board"]}


def _scene(*builders):
    """A floor, the objects, and the benchmark's own physics options."""
    spec = new_spec()
    apply_options(spec, PhysicsOptions())
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    infos = [build(spec) for build in builders]
    model = spec.compile()
    return infos, model, mujoco.MjData(model)


def _step(model, data, seconds=1.0, hold=None):
    """Step; `hold` (a free joint's name) keeps that object's root where it is."""
    if hold is not None:
        qadr, vadr = model.joint(hold).qposadr[0], model.joint(hold).dofadr[0]
        pose = data.qpos[qadr : qadr + 7].copy()
    for _ in range(round(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)
        if hold is not None:
            data.qpos[qadr : qadr + 7], data.qvel[vadr : vadr + 6] = pose, 0.0
    assert np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()


def _place(model, data, info, pos, quat=(1.0, 0.0, 0.0, 0.0)):
    """Put an object's root at a pose: its free joint, or its mocap body."""
    if info.free_joint:
        adr = model.joint(info.free_joint).qposadr[0]
        data.qpos[adr : adr + 7] = [*pos, *quat]
    else:
        mocap = model.body_mocapid[model.body(info.root).id]
        data.mocap_pos[mocap], data.mocap_quat[mocap] = pos, quat
    mujoco.mj_forward(model, data)


def _point(data, info, name):
    body, pos = info.points[name]
    return data.body(body).xpos + data.body(body).xmat.reshape(3, 3) @ pos


def _qpos(model, data, joint):
    return data.qpos[model.joint(joint).qposadr[0]]


def _set_joints(model, data, values):
    for joint, q in values.items():
        if joint in [model.joint(j).name for j in range(model.njnt)]:
            data.qpos[model.joint(joint).qposadr[0]] = q
    mujoco.mj_forward(model, data)


@pytest.mark.parametrize("kind", sorted(set(FREE) - {"hammer"}))
def test_free_assets_rest_stably(kind):
    build, mass = FREE[kind]
    (info,), model, data = _scene(build)
    _check_metadata(info, model)
    assert model.body_subtreemass[model.body(info.root).id] == pytest.approx(mass, rel=0.02)
    _place(model, data, info, [0.1, -0.2, info.rest_height - 5e-4])
    _set_joints(model, data, AJAR)
    assert data.ncon > 0, "rest_height puts the object on the floor"
    assert data.contact.dist[: data.ncon].min() > -0.002, "penetrates at rest"
    adr = model.joint(info.free_joint).qposadr[0]
    start, joints = data.qpos[adr : adr + 7].copy(), {j: _qpos(model, data, j)
                                                      for j in info.joints}
    _step(model, data)
    assert np.linalg.norm(data.qpos[adr : adr + 3] - start[:3]) < 0.003, "drifts at rest"
    assert abs(np.dot(data.qpos[adr + 3 : adr + 7], start[3:])) > math.cos(math.radians(1))
    assert data.ncon == 0 or data.contact.dist[: data.ncon].min() > -0.002
    for joint, q in joints.items():
        assert _qpos(model, data, joint) == pytest.approx(q, abs=0.005), f"{joint} creeps"


@pytest.mark.parametrize("kind", sorted(FIXED))
def test_fixed_assets_are_mocap_with_light_moving_parts(kind):
    (info,), model, data = _scene(FIXED[kind])
    _check_metadata(info, model)
    assert info.mocap and info.free_joint is None
    root = model.body(info.root).id
    for b in range(root + 1, model.nbody):
        assert 0.005 < model.body_mass[b] < 1.0
    _step(model, data)
    for joint in info.joints:  # the nail stays put under its own weight
        assert _qpos(model, data, joint) == pytest.approx(0.0, abs=1e-3)


# (object, joint, generalized effort well above its friction loss and weight)
MECHANISMS = [("folder", "folder/flap", 0.4), ("stapler", "stapler/arm", 0.4),
              ("knife", "knife/blade", 1.5), ("scissors", "scissors/blade0", 0.03),
              ("scissors", "scissors/blade1", 0.03), ("board", "board/nail", 25.0)]


@pytest.mark.parametrize(("kind", "joint", "effort"), MECHANISMS)
def test_mechanisms_reach_both_limits_and_no_further(kind, joint, effort):
    build = FREE[kind][0] if kind in FREE else FIXED[kind]
    (info,), model, data = _scene(build)
    lo, hi = info.joints[joint]
    hold = info.free_joint
    if hold is not None:  # held up in the air, so the parts move freely
        _place(model, data, info, [0.0, 0.0, 0.1])
    dof = model.joint(joint).dofadr[0]
    slack = 0.02 * (hi - lo)  # soft limits: a part slammed into one overshoots briefly
    for sign, limit in ((1.0, hi), (-1.0, lo)):
        data.qfrc_applied[dof] = sign * effort
        for _ in range(5):
            _step(model, data, 0.1, hold)
            assert lo - 2.5 * slack <= _qpos(model, data, joint) <= hi + 2.5 * slack
        assert _qpos(model, data, joint) == pytest.approx(limit, abs=slack)
    data.qfrc_applied[dof] = 0.0
    data.qpos[model.joint(joint).qposadr[0]] = (lo + hi) / 2
    _step(model, data, 0.5, hold)
    assert _qpos(model, data, joint) == pytest.approx((lo + hi) / 2, abs=slack)


@pytest.mark.parametrize(("kind", "joint", "kick"), [("folder", "folder/flap", 3.0),
                                                     ("stapler", "stapler/arm", 3.0),
                                                     ("knife", "knife/blade", 0.3)])
def test_knocked_parts_come_to_rest(kind, joint, kick):
    """Friction-held parts settle after a knock (at `articulated.HOLD` they chatter on)."""
    (info,), model, data = _scene(FREE[kind][0])
    _place(model, data, info, [0.0, 0.0, 0.1])
    lo, hi = info.joints[joint]
    _set_joints(model, data, {joint: (lo + hi) / 2})
    data.qvel[model.joint(joint).dofadr[0]] = kick
    _step(model, data, 1.5, hold=info.free_joint)
    speeds = []
    for _ in range(24):
        _step(model, data, 1 / 240, hold=info.free_joint)
        speeds.append(abs(data.qvel[model.joint(joint).dofadr[0]]))
    assert max(speeds) < 1e-3


def test_nail_barely_yields_to_a_press_below_its_friction():
    """MuJoCo's friction loss is soft: 10 N (of 15) creeps the nail about 2 mm/s."""
    _, model, data = _scene(FIXED["board"])
    data.qfrc_applied[model.joint("board/nail").dofadr[0]] = -10.0
    _step(model, data, 0.5)
    assert _qpos(model, data, "board/nail") > -0.002


def test_hammer_stands_on_its_stand_and_a_strike_drives_the_nail():
    (hammer, stand, board), model, data = _scene(FREE["hammer"][0], FIXED["stand"],
                                                 FIXED["board"])
    _check_metadata(hammer, model)
    _place(model, data, stand, [0.0, 0.0, 0.0])
    _place(model, data, board, [0.0, 0.4, 0.0])
    _place(model, data, hammer, _point(data, stand, "hammer"))
    adr = model.joint("hammer/free").qposadr[0]
    start = data.qpos[adr : adr + 7].copy()
    _step(model, data)
    assert np.linalg.norm(data.qpos[adr : adr + 3] - start[:3]) < 0.003
    assert abs(np.dot(data.qpos[adr + 3 : adr + 7], start[3:])) > math.cos(math.radians(1))
    # Face down, 2 cm over the nail head, coming down at 1.5 m/s: one blow drives it a bit.
    face = np.array(hammer.points["face"][1])
    over = _point(data, board, "nail_head") + [0, 0, 0.02]
    _place(model, data, hammer, over - face)
    data.qvel[model.joint("hammer/free").dofadr[0] + 2] = -1.5
    _step(model, data, 0.3)
    driven = -_qpos(model, data, "board/nail")
    assert 0.003 < driven < 0.05


def test_scissors_close_when_the_rings_are_squeezed():
    (info,), model, data = _scene(FREE["scissors"][0])
    _place(model, data, info, [0.0, 0.0, info.rest_height])
    _set_joints(model, data, AJAR)
    for _ in range(round(0.5 / model.opt.timestep)):
        data.qfrc_applied[:] = 0.0
        for k, sign in ((0, 1.0), (1, -1.0)):  # each ring towards the other
            body = model.body(f"scissors/blade{k}").id
            mujoco.mj_applyFT(model, data, [0, sign * 0.5, 0], [0, 0, 0],
                              _point(data, info, f"ring{k}"), body, data.qfrc_applied)
        mujoco.mj_step(model, data)
    for k in range(2):
        lo, hi = info.joints[f"scissors/blade{k}"]
        assert _qpos(model, data, f"scissors/blade{k}") < lo + 0.5 * (hi - lo)


def _pebble(spec):
    return objects.add_sphere(spec, "pebble", radius=0.01, mass=0.01)


@pytest.mark.parametrize(("kind", "bottom"), [("can", "bottom"), ("pan", "centre")])
def test_open_vessels_hold_a_pebble(kind, bottom):
    """Dropped in, a pebble lands on the inner floor (a few mm up) and stays there."""
    (info, pebble), model, data = _scene(FREE[kind][0], _pebble)
    _place(model, data, pebble, [0.012, 0.0, 0.12])
    _step(model, data)
    pos = data.body("pebble").xpos
    floor = info.points[bottom][1][2]
    assert np.hypot(*pos[:2]) < 0.03 and floor + 0.012 < pos[2] < floor + 0.02


def test_a_pen_stands_in_its_holder_deep_enough_for_insert_pen():
    (pen, holder), model, data = _scene(FREE["pen"][0], FIXED["holder"])
    _place(model, data, holder, [0.0, 0.0, 0.0])
    tip_down = [math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]  # pen's +x (tip) points down
    entrance = _point(data, holder, "entrance")
    _place(model, data, pen, entrance + [0.01, 0.0, 0.075], tip_down)
    _step(model, data)
    tip = _point(data, pen, "tip")
    assert np.hypot(*(tip - entrance)[:2]) < 0.038 and tip[2] < entrance[2] - 0.03


@pytest.mark.parametrize(("kind", "cup_at"), [("stove", "target"), ("rack", "slot")])
def test_pan_on_the_burner_and_cup_in_the_rack_stay(kind, cup_at):
    vessel = FREE["pan"][0] if kind == "stove" else (lambda s: procedural.add_cup(s, "cup"))
    (base, item), model, data = _scene(FIXED[kind], vessel)
    _place(model, data, base, [0.05, -0.05, 0.0], [math.cos(0.3), 0, 0, math.sin(0.3)])
    spot = _point(data, base, cup_at)
    _place(model, data, item, spot + [0, 0, 5e-4])
    _step(model, data)
    assert np.linalg.norm(data.body(item.root).xpos - spot) < 0.003
    assert data.body(item.root).xmat[8] > math.cos(math.radians(1))
    if kind == "rack":  # pushed sideways, the rods keep the cup in the rack
        data.xfrc_applied[model.body("cup").id, :3] = [1.0, 0.3, 0.0]
        _step(model, data, 0.5)
        assert np.linalg.norm(data.body("cup").xpos[:2] - spot[:2]) < 0.015


def test_ramp_ball_rolls_back_down_the_incline_but_rests_past_the_crest():
    def ball(spec):
        return objects.add_sphere(spec, "ball", radius=0.02, mass=0.05)
    (ramp, ball_info), model, data = _scene(FIXED["ramp"], ball)
    _place(model, data, ramp, [0.0, 0.0, 0.0])
    normal = np.array([-math.sin(math.radians(15)), 0, math.cos(math.radians(15))])
    _place(model, data, ball_info, _point(data, ramp, "slot3") + 0.0205 * normal)
    _step(model, data, 1.5)
    target = _point(data, ramp, "target")
    assert data.body("ball").xpos[0] < _point(data, ramp, "slot0")[0]
    _place(model, data, ball_info, target + [0.03, 0.0, 0.0205])
    data.qvel[:] = 0.0
    _step(model, data)
    assert data.body("ball").xpos[0] > target[0] and data.body("ball").xpos[2] > target[2]


@pytest.mark.parametrize("kind", sorted(ZONED))
def test_zone_bodies_hold_exactly_the_no_touch_geoms(kind):
    """Each zone's body is rigid on its object and its geoms lie inside the zone."""
    (info,), model, data = _scene(ZONED[kind])
    mujoco.mj_forward(model, data)
    assert info.zones
    for zone in info.zones:
        body = model.body(zone.body).id
        assert model.body_jntnum[body] == 0 and body != model.body(info.root).id
        geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == body]
        assert geoms
        centre = data.xpos[body] + data.xmat[body].reshape(3, 3) @ zone.pos
        axis = data.xmat[body].reshape(3, 3) @ zone.axis
        for g in geoms:
            rel = data.geom_xpos[g] - centre
            along = rel @ axis
            assert abs(along) <= zone.half_length
            assert np.linalg.norm(rel - along * axis) <= zone.radius
