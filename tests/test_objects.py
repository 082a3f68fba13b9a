"""Procedural objects: they compile, their metadata matches the model, they behave."""

import math

import mujoco
import numpy as np
import pytest

from dexbench.assets import articulated, meshes, objects, procedural
from dexbench.assets.objects import new_spec

FREE_BUILDERS = {
    "box": lambda s: objects.add_free_box(s, "box", [0.025] * 3, 0.1),
    "sphere": lambda s: objects.add_sphere(s, "sphere"),
    "cylinder": lambda s: objects.add_cylinder(s, "cylinder"),
    "capsule": lambda s: objects.add_capsule(s, "capsule"),
    "stick": lambda s: objects.add_stick(s, "stick"),
    "stick_lying": lambda s: objects.add_stick(s, "stick_lying", upright=False),
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
    "hole_up": lambda s: objects.add_hole_block(s, "hole_up", vertical=True),
    "switch": lambda s: articulated.add_switch(s, "switch"),
    "button": lambda s: articulated.add_button(s, "button"),
    "faucet": lambda s: articulated.add_faucet(s, "faucet"),
    "cabinet": lambda s: articulated.add_drawer_cabinet(s, "cabinet"),
    "machine": lambda s: articulated.add_coffee_machine(s, "machine"),
    "goal": lambda s: objects.add_goal_marker(s, "goal"),
    "goal_tee": lambda s: objects.add_t_shape(s, "goal_tee", visual_only=True),
}
MASS = {"box": 0.1, "sphere": 0.1, "cylinder": 0.1, "capsule": 0.1, "stick": 0.1,
        "stick_lying": 0.1, "tray": 0.5, "tee": 0.2, "peg": 0.1, "mug": 0.25, "cup": 0.12,
        "bottle": 0.2, "jar": 0.3, "laptop": 1.2, "milk": 0.305}


def _scene(*builders):
    """A floor, the objects, and the solver settings the benchmark runs with."""
    spec = new_spec()
    spec.option.timestep = 1 / 240
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
    infos = [build(spec) for build in builders]
    model = spec.compile()
    return infos, model, mujoco.MjData(model)


def _step(model, data, seconds=1.0):
    for _ in range(round(seconds / model.opt.timestep)):
        mujoco.mj_step(model, data)
    assert np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()


def _subtree(model, root):
    ids = [root]
    for b in range(root + 1, model.nbody):
        if model.body_parentid[b] in ids:
            ids.append(b)
    return ids


def _check_metadata(info, model):
    """Names follow `<name>/...`, and every field of the info agrees with the model."""
    root = model.body(info.root).id
    assert root > 0 and info.root == info.name
    bodies = _subtree(model, root)
    for b in bodies[1:]:
        assert model.body(b).name.startswith(f"{info.name}/")
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] in bodies]
    assert geoms and all(model.geom(g).name.startswith(f"{info.name}/") for g in geoms)
    joints = [j for j in range(model.njnt) if model.jnt_bodyid[j] in bodies]
    free = [j for j in joints if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    assert [model.joint(j).name for j in free] == ([info.free_joint] if info.free_joint else [])
    assert {model.joint(j).name for j in joints if j not in free} == set(info.joints)
    for joint, (lo, hi) in info.joints.items():
        assert model.jnt_limited[model.joint(joint).id] and lo < hi
        np.testing.assert_allclose(model.joint(joint).range, [lo, hi])
    assert (model.body_mocapid[root] >= 0) == info.mocap
    assert not (info.mocap and info.free_joint)
    for body, vec in (*info.points.values(), *info.axes.values()):
        assert model.body(body).id in bodies and len(vec) == 3
    for _, axis in info.axes.values():
        assert np.linalg.norm(axis) == pytest.approx(1.0)
    for zone in info.zones:
        assert model.body(zone.body).id in bodies and zone.kind in ("sphere", "cylinder")
        assert zone.radius > 0
    for g in geoms:
        if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0:
            assert model.geom_group[g] == 2, "visual-only geoms live in group 2"
        elif info.free_joint:  # balls also resist rolling (condim 6)
            assert model.geom_condim[g] >= 4, "graspable geoms use torsional friction"
    reach = _reach(model, root)
    if reach > 0:  # else nothing collides (goal markers): the footprint is the task's call
        assert reach - 0.003 <= info.footprint_radius <= reach + 0.03, f"measured {reach:.3f}"


def _reach(model, root):
    """How far the object's colliding geoms reach from its root in xy, found by casting
    horizontal rays at it from all around (the root at the origin, at qpos0)."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    groups = np.array([1, 1, 0, 1, 1, 1], dtype=np.uint8)  # group 2 is visual-only
    geom = np.zeros(1, dtype=np.int32)
    reach = 0.0
    for z in np.linspace(0.002, 0.40, 60):
        for a in np.linspace(0, 2 * math.pi, 36, endpoint=False):
            direction = np.array([math.cos(a), math.sin(a), 0.0])
            dist = mujoco.mj_ray(model, data, np.array([0, 0, z]) + direction, -direction,
                                 groups, 1, -1, geom)
            if dist >= 0 and model.geom_bodyid[geom[0]] in _subtree(model, root):
                reach = max(reach, 1.0 - dist)
    return reach


@pytest.mark.parametrize("kind", sorted(FREE_BUILDERS))
def test_free_objects_rest_stably(kind):
    (info,), model, data = _scene(FREE_BUILDERS[kind])
    _check_metadata(info, model)
    assert info.free_joint == f"{kind}/free" and not info.mocap
    mass = model.body_subtreemass[model.body(info.root).id]
    assert mass == pytest.approx(MASS[kind], rel=0.02)
    adr = model.joint(info.free_joint).qposadr[0]
    data.qpos[adr : adr + 3] = [0.1, -0.2, info.rest_height - 5e-4]  # just touching
    if kind == "laptop":
        data.qpos[model.joint("laptop/hinge").qposadr[0]] = math.radians(-15)
    mujoco.mj_forward(model, data)
    assert data.ncon > 0, "rest_height puts the object on the floor"
    assert data.contact.dist[: data.ncon].min() > -0.002, "penetrates at rest"
    start = data.qpos[adr : adr + 7].copy()
    _step(model, data)
    assert np.linalg.norm(data.qpos[adr : adr + 3] - start[:3]) < 0.005, "drifts at rest"
    assert abs(np.dot(data.qpos[adr + 3 : adr + 7], start[3:])) > math.cos(math.radians(1))
    if kind == "laptop":  # the friction hinge holds the lid up
        lid = data.qpos[model.joint("laptop/hinge").qposadr[0]]
        assert lid == pytest.approx(math.radians(-15), abs=math.radians(2))


@pytest.mark.parametrize("kind", sorted(FIXED_BUILDERS))
def test_fixed_objects_are_mocap_and_joints_stay_in_range(kind):
    (info,), model, data = _scene(FIXED_BUILDERS[kind])
    _check_metadata(info, model)
    assert info.mocap and info.free_joint is None
    for b in _subtree(model, model.body(info.root).id)[1:]:
        assert 0.005 < model.body_mass[b] < 1.0
    _step(model, data)
    for joint, (lo, hi) in info.joints.items():
        assert lo - 1e-3 <= data.qpos[model.joint(joint).qposadr[0]] <= hi + 1e-3


@pytest.mark.parametrize("shape", sorted(objects.PRIMITIVE_SHAPES))
def test_primitive_set_shapes(shape):
    (infos,), model, data = _scene(lambda s: objects.add_primitive_set(s, [shape]))
    (info,) = infos.values()
    _check_metadata(info, model)
    adr = model.joint(info.free_joint).qposadr[0]
    data.qpos[adr + 2] = info.rest_height
    _step(model, data)
    assert abs(data.qpos[adr + 2] - info.rest_height) < 0.002


def test_button_springs_back():
    (info,), model, data = _scene(FIXED_BUILDERS["button"])
    lo, hi = info.joints["button/press"]
    assert lo < 0 == hi, "pressed is negative"
    adr = model.joint("button/press").qposadr[0]
    data.qpos[adr] = lo
    _step(model, data, 0.5)
    assert data.qpos[adr] > -0.001


@pytest.mark.parametrize(("kind", "joint", "where"),
                         [("cabinet", "cabinet/drawer", 0.1), ("faucet", "faucet/handle", 1.0),
                          ("machine", "machine/lever", 0.6), ("switch", "switch/rocker", -0.35)])
def test_mechanisms_stay_where_left(kind, joint, where):
    _, model, data = _scene(FIXED_BUILDERS[kind])
    adr = model.joint(joint).qposadr[0]
    data.qpos[adr] = where
    _step(model, data)
    assert data.qpos[adr] == pytest.approx(where, abs=0.005)


def test_lathe_mesh_counts_and_outward_normals():
    profile = [(0, 0), (0.05, 0), (0.05, 0.1), (0, 0.1)]
    verts, faces = meshes.lathe_mesh(profile, 24)
    assert verts.shape == (4 * 24, 3) and faces.shape == (2 * 3 * 24, 3)
    polygon = math.pi * 0.05**2 * math.sin(2 * math.pi / 24) * 24 / (2 * math.pi)
    assert meshes.mesh_volume(verts, faces) == pytest.approx(polygon * 0.1)


def test_hollow_shell_and_pieces_are_outward_and_convex():
    spec = new_spec()
    procedural.add_mug(spec, "mug")
    procedural.add_bottle(spec, "bottle")
    for mesh in spec.meshes:
        verts = np.asarray(mesh.uservert).reshape(-1, 3)
        faces = np.asarray(mesh.userface).reshape(-1, 3)
        assert meshes.mesh_volume(verts, faces) > 0, mesh.name
        if mesh.name.endswith("/visual"):
            continue
        a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
        normals = np.cross(b - a, c - a)
        keep = np.linalg.norm(normals, axis=1) > 1e-12
        heights = np.einsum("fj,vj->fv", normals[keep], verts) - np.einsum(
            "fj,fj->f", normals[keep], a[keep])[:, None]
        assert heights.max() < 1e-9, f"{mesh.name} is not convex"
    # The mug's wall volume is that of a 6 mm shell: sectors and bottom are not solid.
    wall = next(m for m in spec.meshes if m.name == "mug/wall0")
    vol = meshes.mesh_volume(np.asarray(wall.uservert).reshape(-1, 3),
                             np.asarray(wall.userface).reshape(-1, 3)) * 16
    assert vol == pytest.approx(math.pi * (0.04**2 - 0.034**2) * 0.087, rel=0.05)


def test_convex_runs_split_a_bottle_at_its_neck():
    runs = meshes.convex_runs([(0.028, 0), (0.03, 0.01), (0.03, 0.1), (0.012, 0.15),
                               (0.012, 0.18)])
    assert [len(r) for r in runs] == [4, 2] and runs[0][-1] == runs[1][0]


@pytest.mark.parametrize("vessel", ["mug", "cup", "jar"])
def test_open_vessels_hold_a_small_sphere(vessel):
    def pebble(spec):
        return objects.add_sphere(spec, "pebble", radius=0.01, mass=0.01)
    (info, _), model, data = _scene(FREE_BUILDERS[vessel], pebble)
    adr = model.joint("pebble/free").qposadr[0]
    rim = info.points["rim"][1]
    data.qpos[adr : adr + 3] = [0.012, 0.0, rim[2] + 0.02]
    _step(model, data)
    pebble_pos = data.qpos[adr : adr + 3]
    assert np.hypot(*pebble_pos[:2]) < 0.035 and 0.014 < pebble_pos[2] < 0.03


def test_t_shape_footprint_area():
    polys = objects.t_shape_polygons()
    x, y = np.concatenate([p[:, 0] for p in polys]), np.concatenate([p[:, 1] for p in polys])
    areas = [0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
             for p in polys]
    assert min(areas) > 0, "counter-clockwise"
    assert sum(areas) == pytest.approx(0.2 * 0.05 + 0.05 * 0.15)
    assert x.max() - x.min() == pytest.approx(0.2) and y.max() - y.min() == pytest.approx(0.2)


@pytest.mark.parametrize("vertical", [False, True])
def test_peg_fits_the_hole(vertical):
    """Centred on the bore with its head at the target, the peg touches nothing."""
    def hole(spec):
        return objects.add_hole_block(spec, "hole", vertical=vertical)
    (peg, hole_info), model, data = _scene(FREE_BUILDERS["peg"], hole)
    target = np.array(hole_info.points["target"][1])
    bore = np.array(hole_info.axes["bore"][1])
    adr = model.joint("peg/free").qposadr[0]
    quat = [1.0, 0, 0, 0] if not vertical else [math.sqrt(0.5), 0, math.sqrt(0.5), 0]
    head = np.array(peg.points["head"][1])
    data.qpos[adr : adr + 7] = [*(target + bore * 0.002 + bore * head[0]), *quat]
    mujoco.mj_forward(model, data)
    assert data.ncon == 0
    if vertical:  # it stands in the hole under gravity, head at the bottom
        _step(model, data)
        tip = data.qpos[adr : adr + 3] - bore * head[0]
        lateral = np.hypot(*(tip - target)[:2])
        assert lateral < 0.023 and abs(tip[2] - target[2]) < 0.01
