"""Procedural objects: they compile, their metadata matches the model, they behave."""

import math

import mujoco
import numpy as np
import pytest

from dexbench.assets import articulated, objects, procedural
from dexbench.assets.objects import new_spec

FREE_BUILDERS = {
    "box": lambda s: objects.add_free_box(s, "box", [0.025] * 3, 0.1),
    "sphere": lambda s: objects.add_sphere(s, "sphere"),
    "stick": lambda s: objects.add_stick(s, "stick"),
    "tray": lambda s: objects.add_tray(s, "tray"),
    "tee": lambda s: objects.add_t_shape(s, "tee"),
    "peg": lambda s: objects.add_peg(s, "peg"),
    "mug": lambda s: procedural.add_mug(s, "mug"),
    "cup": lambda s: procedural.add_cup(s, "cup"),
    "bottle": lambda s: procedural.add_bottle(s, "bottle"),
    "jar": lambda s: procedural.add_jar(s, "jar"),
    "laptop": lambda s: articulated.add_laptop(s, "laptop"),
    "milk": lambda s: articulated.add_milk_carton(s, "milk"),
}
FIXED_BUILDERS = {
    "hole": lambda s: objects.add_hole_block(s, "hole"),
    "switch": lambda s: articulated.add_switch(s, "switch"),
    "button": lambda s: articulated.add_button(s, "button"),
    "faucet": lambda s: articulated.add_faucet(s, "faucet"),
    "cabinet": lambda s: articulated.add_drawer_cabinet(s, "cabinet"),
    "machine": lambda s: articulated.add_coffee_machine(s, "machine"),
    "goal": lambda s: objects.add_goal_marker(s, "goal"),
}


def _scene(builder):
    spec = new_spec()
    spec.option.timestep = 1 / 240
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    info = builder(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    return info, model, data


def _metadata_matches(info, model):
    assert model.body(info.root).id > 0
    for joint, (lo, hi) in info.joints.items():
        np.testing.assert_allclose(model.joint(joint).range, [lo, hi])
    for body, _ in (*info.points.values(), *info.axes.values()):
        assert model.body(body).id > 0
    for zone in info.zones:
        assert model.body(zone.body).id > 0 and zone.kind in ("sphere", "cylinder")


@pytest.mark.parametrize("kind", sorted(FREE_BUILDERS))
def test_free_objects_rest_stably(kind):
    info, model, data = _scene(FREE_BUILDERS[kind])
    _metadata_matches(info, model)
    assert info.free_joint and not info.mocap
    mass = model.body_subtreemass[model.body(info.root).id]
    assert 0.02 < mass < 3.0
    adr = model.joint(info.free_joint).qposadr[0]
    data.qpos[adr : adr + 3] = [0.1, -0.2, info.rest_height + 1e-4]
    if kind == "laptop":
        data.qpos[model.joint("laptop/hinge").qposadr[0]] = math.radians(-15)
    mujoco.mj_forward(model, data)
    assert data.contact.dist[: data.ncon].min(initial=0.0) > -0.002, "penetrates at rest"
    start = data.qpos[adr : adr + 3].copy()
    for _ in range(240):
        mujoco.mj_step(model, data)
    assert np.isfinite(data.qpos).all()
    assert np.linalg.norm(data.qpos[adr : adr + 3] - start) < 0.005, "drifts when resting"


@pytest.mark.parametrize("kind", sorted(FIXED_BUILDERS))
def test_fixed_objects_are_mocap_and_joints_stay_in_range(kind):
    info, model, data = _scene(FIXED_BUILDERS[kind])
    _metadata_matches(info, model)
    assert info.mocap and info.free_joint is None
    assert model.body(info.root).mocapid[0] >= 0
    for _ in range(240):
        mujoco.mj_step(model, data)
    for joint, (lo, hi) in info.joints.items():
        q = data.qpos[model.joint(joint).qposadr[0]]
        assert lo - 1e-3 <= q <= hi + 1e-3


def test_button_springs_back():
    _, model, data = _scene(FIXED_BUILDERS["button"])
    adr = model.joint("button/press").qposadr[0]
    data.qpos[adr] = -0.014
    for _ in range(240):
        mujoco.mj_step(model, data)
    assert data.qpos[adr] > -0.002


def test_drawer_stays_where_left():
    _, model, data = _scene(FIXED_BUILDERS["cabinet"])
    adr = model.joint("cabinet/drawer").qposadr[0]
    data.qpos[adr] = 0.1
    for _ in range(240):
        mujoco.mj_step(model, data)
    assert abs(data.qpos[adr] - 0.1) < 0.005


def test_lathe_mesh_is_outward_and_closed_volume_positive():
    verts, faces = procedural.lathe_mesh([(0, 0), (0.05, 0), (0.05, 0.1), (0, 0.1)], 24)
    assert verts.shape == (4 * 24, 3) and faces.shape == (3 * 24 * 2, 3)
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6
    assert volume == pytest.approx(math.pi * 0.05**2 * 0.1, rel=0.02)


def test_mug_holds_a_small_sphere():
    def builder(spec):
        info = procedural.add_mug(spec, "mug")
        objects.add_sphere(spec, "pebble", radius=0.01, mass=0.01)
        return info
    _, model, data = _scene(builder)
    adr = model.joint("pebble/free").qposadr[0]
    data.qpos[adr : adr + 3] = [0.01, 0.0, 0.08]
    for _ in range(240):
        mujoco.mj_step(model, data)
    pebble = data.qpos[adr : adr + 3]
    assert np.hypot(*pebble[:2]) < 0.04 and pebble[2] < 0.05


def test_t_shape_footprint_area():
    area = sum(4 * hx * hy for _, _, hx, hy in objects.T_SHAPE_RECTS)
    assert area == pytest.approx(0.2 * 0.05 + 0.05 * 0.15)
