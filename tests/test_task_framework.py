"""The task framework (registration, plans as data, embodiment accessors) and the fidelity
fixes of issue 17, each tested against the state that showed the bug."""

import math
import pathlib
import re

import mujoco
import numpy as np
import pytest
import torch
import yaml

from dexbench.embodiments.builder import embodiment_arity, other_hands
from dexbench.envs.dex_env import DexEnv
from dexbench.tasks import plans
from dexbench.tasks.articulation import OpenDrawer
from dexbench.tasks.functional import FunctionalPourMug
from dexbench.tasks.primitive import PickUpStick, RelocateSphere, TurnOnSwitch
from dexbench.tasks.registry import TASKS, make_env
from dexbench.tasks.templates import (
    ADDON_LIFT,
    MAX_SPEED,
    MultiGoalTask,
    Placement,
    Stage,
    StageTask,
)

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAPER = ROOT.parent / "shared" / "seed" / "dexverse_paper.tex"
# The paper's appendix "Task List": 61 single tasks (OvenBake written with \text{}) ...
PAPER_SINGLE = {
    "primitive": ["PickCube", "StackCube", "RelocateSphere", "PickUpStick", "RelocateObject",
                  "TurnOnSwitch", "PushButton", "OpenFaucet", "GraspTwoItems"],
    "articulation": ["OpenCabinet", "LiftLid", "OpenDoor", "RotateKnob", "OpenMicrowave",
                     "OpenDrawer", "GraspBucket", "GraspPot", "OpenLaptop", "SqueezeScissors",
                     "SlideUtilityKnife", "LiftBasketHandle", "OpenStapler", "OpenFlatFolder",
                     "OpenPhone", "OpenDoubleDoor", "UnscrewCap", "OpenGlasses"],
    "functional": ["GraspBleach", "GraspPan", "GraspKettle", "GraspCup", "RetrieveCup",
                   "LiftBucket", "FunctionalPourCan", "FunctionalPourMug",
                   "FunctionalHammerStrike", "FunctionalDrillApply", "PourWineGlass"],
    "contact_rich": ["NutThread", "InsertPipette", "PlugCharger", "InsertPen", "InsertGear",
                     "InsertPeg", "PickFromClutter", "PickThinObjectFromContainer"],
    "nonprehensile": ["PushSphereUpSlope", "PushSmallSphereObstacleSlope", "PushT",
                      "PivotLargeCuboidAgainstWall", "TakeBookOffShelf"],
    "bimanual": ["BimanualLiftTray", "BimanualLiftBasket", "BimanualLiftCarton",
                 "BimanualLiftDutchOven", "BimanualHandover"],
    "longhorizon": ["CookFood", "MakeCoffee", "MicrowaveFood", "OvenBake", "CleanTable"],
}
# ... and 39 multi-goal variants: 9 primaries x 4 add-ons, plus PourMug x the other 3.
PRIMARIES = ["OpenMicrowave", "OpenDoor", "OpenDrawer", "LiftLid", "GraspPot", "PushButton",
             "RotateKnob", "TurnOnSwitch", "GraspBucket"]
ADDONS = ["PourCan", "PickUpStick", "PourMug", "RelocateSphere"]
PAPER_NAMES = {n for names in PAPER_SINGLE.values() for n in names} | {
    f"{p}_{a}" for p in [*PRIMARIES, "PourMug"] for a in ADDONS if p != a}


def _splits() -> dict[str, dict[str, list[str]]]:
    return {f.stem: yaml.safe_load(f.read_text())["categories"]
            for f in sorted((ROOT / "conf" / "split").glob("*.yaml"))}


def test_paper_names_are_the_100_of_the_appendix():
    assert len(PAPER_NAMES) == 100
    if not PAPER.exists():
        pytest.skip("the paper's source is not next to this checkout")
    table = PAPER.read_text().split("Task List and Visualization")[1].split("\\end{longtable}")[0]
    cells = re.findall(r"^\s*& (\\shortstack\[l\]\{.*?\}|\\text(?:tt)?\{\w+\})\s*$", table,
                       flags=re.M)
    names = {"".join(re.findall(r"\\text(?:tt)?\{(\w+)\}", c)) for c in cells}
    assert names == {n for ns in PAPER_SINGLE.values() for n in ns}


def test_every_split_names_only_paper_tasks_and_the_category_splits_cover_them():
    splits = _splits()
    for name, categories in splits.items():
        tasks = [t for ts in categories.values() for t in ts]
        assert len(tasks) == len(set(tasks)), name
        assert set(tasks) <= PAPER_NAMES, (name, set(tasks) - PAPER_NAMES)
    everything = {t for ts in splits["all"].values() for t in ts}
    assert everything == PAPER_NAMES
    for category, names in PAPER_SINGLE.items():
        assert splits[category][category] == names
        assert splits["all"][category] == names
    assert len(splits["baseline19"]) and sum(map(len, splits["baseline19"].values())) == 19


def test_tasks_register_themselves_and_every_one_has_its_plan():
    assert set(TASKS) <= PAPER_NAMES
    for name, cls in TASKS.items():
        assert cls.name == name and cls.expert is not None, name
    source = (ROOT / "dexbench" / "tasks" / "registry.py").read_text()
    assert "TASK_CLASSES" not in source and "PickCube" not in source


def test_embodiment_accessors_carry_mount_hand_and_arity():
    env = make_env("OpenLaptop", "bimanual_fr3_allegro", num_envs=1, nthread=1)
    emb = env.embodiment
    assert (emb.mount, emb.hand.name, emb.arity, emb.bimanual) == ("fr3", "allegro", 2, True)
    assert embodiment_arity("floating_leap") == 1
    assert other_hands("floating_shadow") == [
        "floating_allegro", "floating_leap", "floating_sharpa", "floating_inspire",
        "floating_wuji"]
    assert all(n.startswith("bimanual_xarm7_") for n in other_hands("bimanual_xarm7_wuji"))


def test_plan_points_are_read_from_the_objects():
    env = make_env("OpenDrawer", num_envs=1, nthread=1)
    objects = env.task.objects
    assert plans.locate(objects, "cabinet", "handle") == objects["cabinet"].points["handle"]
    body, local = plans.locate(objects, "cabinet", ("handle", (0.0, 0.0, 0.01)))
    assert body == "cabinet/drawer"
    assert local[2] == pytest.approx(objects["cabinet"].points["handle"][1][2] + 0.01)
    assert plans.locate(objects, "cabinet", (0.1, 0.0, 0.0)) == ("cabinet", (0.1, 0.0, 0.0))


class _SwitchAndStick(MultiGoalTask):
    name, instruction = "TurnOnSwitch_PickUpStick", "Turn on the switch and lift the stick."
    primary_cls, addon_cls, addon_object = TurnOnSwitch, PickUpStick, "stick"
    addon_placement = Placement((-0.20, -0.10), (0.25, 0.35))


class _MugAndBall(MultiGoalTask):
    name, instruction = "PourMug_RelocateSphere", "Pour the mug and lift the ball."
    primary_cls, addon_cls, addon_object = FunctionalPourMug, RelocateSphere, "sphere"
    addon_placement = Placement((-0.25, -0.15), (0.36, 0.46))


def _composite(cls) -> DexEnv:
    env = DexEnv(cls(), "floating_shadow", num_envs=2, seed=0, nthread=1)
    env.reset()
    return env


def test_multigoal_primary_resets_at_its_own_initial_joint():
    env = _composite(_SwitchAndStick)
    lo = env.task.joint_range("switch/rocker")[0]
    assert env.task.initial_joints["switch/rocker"] == lo
    assert env.view.joint_pos("switch/rocker").tolist() == pytest.approx([lo, lo], abs=1e-3)
    assert not env.task.primary.success(env.view).any()


def test_multigoal_builds_with_two_goal_tasks_and_no_addon_marker_at_the_origin():
    env = _composite(_MugAndBall)
    assert set(env.task.objects) == {"mug", "sphere"}
    marker = env.view.body_pos(env.task.markers["goal"].root)
    np.testing.assert_allclose(marker.numpy(), env.view.goal[:, :3].numpy())
    state = env.task.state_obs(env.view)
    assert state.shape[1] == sum(7 + 3 * len(o.points) + len(o.joints)
                                 for o in env.task.objects.values())


def _lift_at(env, obj: str, dz: float, speed: float) -> None:
    info = env.task.objects[obj]
    model = env.scene.model
    adr, dof = model.joint(info.free_joint).qposadr[0], model.joint(info.free_joint).dofadr[0]
    pos = env.view.initial_body_pos[info.root][0]
    env.sim.field("qpos")[0, adr:adr + 3] = pos + torch.tensor([0.0, 0.0, dz],
                                                                 dtype=pos.dtype)
    env.sim.field("qvel")[0, dof:dof + 6] = 0.0
    env.sim.field("qvel")[0, dof + 2] = speed
    env.sim.forward(torch.arange(env.num_envs))


def test_multigoal_addon_lift_has_the_shared_threshold_and_speed_limit():
    env = make_env("OpenDrawer_RelocateSphere", num_envs=1, seed=0, nthread=1)
    env.reset()
    _lift_at(env, "sphere", ADDON_LIFT + 0.01, 0.0)
    assert env.task.addon_lifted(env.view)[0]
    _lift_at(env, "sphere", ADDON_LIFT + 0.01, MAX_SPEED + 0.5)
    assert not env.task.addon_lifted(env.view)[0], "thrown, not lifted"
    _lift_at(env, "sphere", ADDON_LIFT - 0.01, 0.0)
    assert not env.task.addon_lifted(env.view)[0]


def test_grasptwoitems_needs_its_items_held_not_thrown():
    env = make_env("GraspTwoItems", num_envs=1, seed=0, nthread=1)
    env.reset()
    on_table = [n for n in env.task.candidates
                if env.view.initial_body_pos[env.task.objects[n].root][0, 2] > 0.5]
    _lift_at(env, on_table[0], 0.25, 0.0)
    _lift_at(env, on_table[1], 0.25, 0.0)
    assert env.task.success(env.view)[0]
    _lift_at(env, on_table[1], 0.25, MAX_SPEED + 0.5)
    assert not env.task.success(env.view)[0]


def test_grasptwoitems_parked_shapes_are_out_of_every_cameras_view():
    env = make_env("GraspTwoItems", num_envs=1, seed=0, nthread=1)
    env.reset()
    model, data = env.scene.model, env.sim.batch.get_data(0)
    parked = [n for n in env.task.candidates if data.body(n).xpos[2] < 0.5]
    assert len(parked) == 3
    geoms = {g for n in parked for g in np.flatnonzero(model.geom_bodyid == model.body(n).id)}
    with mujoco.Renderer(model, 96, 96) as renderer:
        renderer.enable_segmentation_rendering()
        for cam in range(model.ncam):
            renderer.update_scene(data, camera=cam)
            seg = renderer.render()[..., 0]
            seen = set(np.unique(seg[seg >= 0]).tolist())
            assert not seen & geoms, model.camera(cam).name


def test_contact_group_reports_the_named_objects_whole_subtree():
    env = make_env("OpenDrawer", num_envs=1, seed=0, nthread=1, obs=["contact"])
    model = env.scene.model
    sensor = model.sensor(env.scene.contact_sensors[0])
    assert sensor.objtype[0] == mujoco.mjtObj.mjOBJ_XBODY  # the cabinet and its drawer
    assert model.body(sensor.objid[0]).name == "cabinet"
    two = make_env("GraspTwoItems", num_envs=1, seed=0, nthread=1)
    names = {model_name.split(":contact:")[1] for model_name in two.scene.contact_sensors}
    assert names == set(two.task.candidates)


def _thick_geom_at(env, offset) -> int:
    """Move the floating hand so its thickest geom's centre is at `offset` (radial, 0,
    along) times (the zone's radius or half length + the geom's thickness) from the
    rim zone's centre; return that geom's index."""
    view = env.view
    thick = int(view.hand_geom_thickness.argmax())
    grow = float(view.hand_geom_thickness[thick])
    zone = env.task.objects["mug"].zones[0]
    rim = view.point_pos(zone.body, zone.pos)[0].numpy()
    target = rim + np.array([offset[0] * (zone.radius + grow), 0.0,
                             offset[1] * (zone.half_length + grow)])
    geom = view.hand_geom_pos()[0, thick].numpy()
    for k, axis in enumerate("xyz"):
        joint = f"right/wrist/{axis}"
        q = float(view.joint_pos(joint)[0])
        env.sim.field("qpos")[0, env.scene.model.joint(joint).qposadr[0]] = q + (target - geom)[k]
    env.sim.forward(torch.arange(env.num_envs))
    return thick


def test_no_touch_zone_needs_a_contact_not_nearness():
    env = make_env("FunctionalPourMug", num_envs=1, seed=0, nthread=1)
    env.reset()
    # Diagonally above the rim's edge: the old test (geom centre inside the zone grown by
    # the geom's thickness, 7 cm for this one) called it touching; nothing touches.
    _thick_geom_at(env, (0.95, 0.95))
    data = env.sim.batch.get_data(0)
    mug, hand = env.scene.model.body("mug").id, set(env.scene.hand_geoms)
    bodies = env.scene.model.geom_bodyid
    hand_on_mug = [c for c in data.contact[: data.ncon] if {c.geom1, c.geom2} & hand
                   and mug in (bodies[c.geom1], bodies[c.geom2])]
    assert not hand_on_mug
    assert not env.task.touched(env.view, "mug")[0]
    _thick_geom_at(env, (0.95, 0.0))  # level with the rim, pressed into it
    assert env.task.touched(env.view, "mug")[0]


class _Steps(StageTask):
    name, instruction = "TwoStages", "test"
    stages = (Stage("placed", final=True), Stage("lever", event=True, final=True))

    def __init__(self):
        super().__init__()
        self.now = torch.zeros(1, 2, dtype=torch.bool)

    def make_objects(self, spec):
        return {}

    def conditions(self, view):
        return self.now


class _View:
    def __init__(self):
        self.memory = torch.zeros(1, 2, dtype=torch.float64)
        self._constants = {}

    def constant(self, key, values):
        return self._constants.setdefault(key, torch.as_tensor(values, dtype=torch.float64))


def _run(task, view, *states) -> int:
    for placed, lever in states:
        task.now = torch.tensor([[placed, lever]])
        task.update(view)
    return int(task.completed(view)[0])


def test_stage_events_must_newly_happen_and_state_stages_may_already_hold():
    task, view = _Steps(), _View()
    # The lever turned first (it stays there) and the mug placed: no lever event yet.
    assert _run(task, view, (False, True), (True, True), (True, True)) == 1
    assert not task.success(view)[0]
    # Back below and over again: the event.
    assert _run(task, view, (True, False), (True, True)) == 2
    assert task.success(view)[0]
    task.now = torch.tensor([[False, True]])
    assert not task.success(view)[0], "final conditions must still hold"


def test_makecoffee_lever_turned_first_does_not_count():
    env = make_env("MakeCoffee", num_envs=1, seed=0, nthread=1)
    env.reset()
    task, view = env.task, env.view
    model = env.scene.model

    def update():
        env.sim.forward(torch.arange(1))
        task.update(view)
        return int(task.completed(view)[0])

    lever = model.joint(task.lever).qposadr[0]
    env.sim.field("qpos")[0, lever] = task.initial_joints[task.lever] + math.radians(40)
    _pour(env)
    assert update() == 1
    _place(env)
    assert update() == 2
    for _ in range(3):
        assert update() == 2, "the lever was turned before: not an event"
    assert not task.success(view)[0]
    env.sim.field("qpos")[0, lever] = task.initial_joints[task.lever]
    assert update() == 2
    env.sim.field("qpos")[0, lever] = task.initial_joints[task.lever] + math.radians(40)
    assert update() == 3 and task.success(view)[0]
    _set_free(env, "mug", view.initial_body_pos["mug"][0].numpy())
    env.sim.forward(torch.arange(1))
    assert not task.success(view)[0], "the mug must still be in place"


def _set_free(env, obj, pos, quat=(1.0, 0.0, 0.0, 0.0)):
    adr = env.scene.model.joint(env.task.objects[obj].free_joint).qposadr[0]
    env.sim.field("qpos")[0, adr:adr + 7] = torch.tensor([*pos, *quat], dtype=torch.float64)


def _place(env):
    spot = env.task.point(env.view, "machine", "cup_spot")[0].numpy()
    _set_free(env, "mug", spot + [0.03, 0.0, 0.0])


def _pour(env, lean: float = 80.0, above: float = 0.05):
    """The carton tipped `lean` deg about world y (+: its top towards +x), its spout
    `above` m over the rim."""
    env.sim.forward(torch.arange(1))
    rim = env.task.point(env.view, "mug", "rim")[0].numpy()
    half = math.radians(lean) / 2
    quat = (math.cos(half), 0.0, math.sin(half), 0.0)
    _set_free(env, "milk", [0.0, 0.0, 1.0], quat)
    env.sim.forward(torch.arange(1))
    spout = env.task.point(env.view, "milk", "spout")[0].numpy()
    root = env.view.body_pos("milk")[0].numpy()
    _set_free(env, "milk", rim + [0.0, 0.0, above] - (spout - root), quat)
    env.sim.forward(torch.arange(1))


def test_makecoffee_pour_needs_the_tilt_towards_the_mug_and_the_spout_near_it():
    env = make_env("MakeCoffee", num_envs=1, seed=0, nthread=1)
    env.reset()
    _pour(env)
    towards = bool(env.task.poured(env.view)[0])
    _pour(env, lean=-80.0)
    away = bool(env.task.poured(env.view)[0])
    assert towards != away, "only the lean to the spout's side pours out of the spout"
    lean = 80.0 if towards else -80.0
    _pour(env, lean=lean, above=0.3)
    assert not env.task.poured(env.view)[0], "spout far above the rim"
    _pour(env, lean=lean, above=0.05)
    assert env.task.poured(env.view)[0]


def test_docs_state_where_a_threshold_is_not_the_papers():
    for name in ("PickCube", "GraspTwoItems", "OpenDrawer_RelocateSphere", "MakeCoffee"):
        assert "Not in the paper" in TASKS[name].success_doc() or "Ours" in (
            TASKS[name].success_doc()), name
    assert TASKS["OpenDrawer"].success_doc() == OpenDrawer.success_text


def test_focus_point_is_where_the_reach_reward_leads():
    """`focus_point` (object, point) is the hand's target for the reach reward; without
    it, the first object's body."""
    env = make_env("OpenDrawer", num_envs=2, seed=0, nthread=1)
    env.reset()
    view, task = env.view, env.task
    assert OpenDrawer.focus_point == ("cabinet", "handle")
    assert torch.equal(task.focus(view), task.point(view, "cabinet", "handle"))
    env = make_env("OpenFaucet", num_envs=2, seed=0, nthread=1)
    env.reset()
    assert env.task.focus_point is None
    first = next(iter(env.task.objects.values())).root
    assert torch.equal(env.task.focus(env.view), env.view.body_pos(first))
