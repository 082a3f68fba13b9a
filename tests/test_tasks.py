"""Every task builds, resets cleanly and runs; every success predicate is exercised.

Predicate tests set simulator state directly: one state where the task must succeed and,
for each condition of the paper's success rule, a state violating only that condition.
"""

import functools
import math
import traceback

import numpy as np
import pytest
import torch
from torch.overrides import TorchFunctionMode

from dexbench.cli.docs import docs_path, tasks_markdown, thumbs_path
from dexbench.tasks.multigoal import VARIANTS
from dexbench.tasks.registry import TASKS, make_env


def _one_variant_per_primary() -> set[str]:
    """A generated multi-goal variant per primary, the add-ons taken in turn."""
    by_primary: dict[str, list[str]] = {}
    for name in sorted(VARIANTS):
        by_primary.setdefault(name.split("_")[0], []).append(name)
    return {names[k % len(names)] for k, names in enumerate(by_primary.values())}


# Every task but the generated multi-goal variants, which share their primary's and
# add-on's code: of those, one per primary (each variant builds and resets below).
TASK_KINDS = sorted(set(TASKS) - set(VARIANTS) | _one_variant_per_primary())

PENETRATION_LIMIT = 0.002  # m


def _embodiments(name: str) -> list[str]:
    prefix = "bimanual_" if TASKS[name].bimanual else ""
    return [f"{prefix}floating_shadow", f"{prefix}fr3_shadow"]


@pytest.mark.parametrize("name, embodiment",
                         [(t, e) for t in TASKS for e in _embodiments(t)])
def test_task_builds_resets_without_penetration_and_runs(name, embodiment):
    env = make_env(name, embodiment, num_envs=100, seed=11)
    env.reset()
    worst = min((float(d.contact.dist[: d.ncon].min()) if d.ncon else 0.0)
                for d in (env.sim.batch.get_data(i) for i in range(env.num_envs)))
    assert worst > -PENETRATION_LIMIT, f"{name}: interpenetration {worst * 1e3:.1f} mm at reset"
    small = make_env(name, embodiment, num_envs=4, seed=3)
    small.reset()
    action = small.home_action.repeat(4, 1)
    for _ in range(120):  # 2 s at 60 Hz
        obs, reward, *_ = small.step(action)
    assert all(torch.isfinite(v).all() for v in obs.values()) and torch.isfinite(reward).all()
    assert torch.isfinite(small.sim.field("qpos")).all()


_FACTORIES = {torch.arange, torch.zeros, torch.ones, torch.full, torch.empty, torch.eye,
              torch.linspace}
_STEP_CODE = ("dexbench/tasks/", "dexbench/envs/task_api.py", "dexbench/envs/observations.py",
              "dexbench/rl/rewards.py")


class _HostTensorSpy(TorchFunctionMode):
    """Records, in task and observation code, tensors made from host data, factories
    without a device and indexing with lists or arrays. On the GPU backend each one is a
    host-to-GPU copy that makes the step wait for its physics."""

    def __init__(self) -> None:
        super().__init__()
        self.found: list[str] = []

    def __torch_function__(self, func, types, args=(), kwargs=None):
        kwargs = kwargs or {}
        if self._from_host(func, args, kwargs):
            frames = [f for f in traceback.extract_stack()[:-1] if "dexbench/" in f.filename]
            if frames and any(code in frames[-1].filename for code in _STEP_CODE):
                self.found.append(f"{frames[-1].filename.split('dexbench/')[-1]}:"
                                  f"{frames[-1].lineno} {frames[-1].line}")
        return func(*args, **kwargs)

    @staticmethod
    def _from_host(func, args, kwargs) -> bool:
        if func in (torch.tensor, torch.as_tensor):
            return not isinstance(args[0], torch.Tensor)
        if func in _FACTORIES:
            return kwargs.get("device") is None
        if func is torch.Tensor.__getitem__:
            index = args[1] if isinstance(args[1], tuple) else (args[1],)
            return any(isinstance(i, (list, np.ndarray)) for i in index)
        return False


@pytest.mark.parametrize("name", TASK_KINDS)
def test_task_step_builds_no_tensors_from_host_data(name):
    groups = ["policy", "proprio", "contact", "state", "privileged", "goal"]
    env = make_env(name, num_envs=2, seed=0, obs=groups)
    env.reset()
    action = env.home_action.repeat(2, 1)
    env.step(action)  # the first step may fill caches (made once, on the device)
    with _HostTensorSpy() as spy:
        for _ in range(3):
            env.step(action)
    assert not spy.found, sorted(set(spy.found))


@functools.cache
def _env(name: str):
    env = make_env(name, num_envs=1, seed=0)
    env.reset()
    return env


def _fresh(name: str):
    env = _env(name)
    env.reset()
    return env


def _quat_about(axis: str, degrees: float) -> list[float]:
    half = math.radians(degrees) / 2
    vec = {"x": [1, 0, 0], "y": [0, 1, 0], "z": [0, 0, 1]}[axis]
    return [math.cos(half), *(math.sin(half) * np.array(vec))]


def _set_pose(env, obj: str, pos, quat=(1.0, 0.0, 0.0, 0.0)) -> None:
    info = env.task.objects[obj]
    adr = env.scene.model.joint(info.free_joint).qposadr[0]
    env.sim.field("qpos")[0, adr : adr + 7] = torch.tensor([*pos, *quat], dtype=torch.float64)


def _set_joint(env, joint: str, value: float) -> None:
    env.sim.field("qpos")[0, env.scene.model.joint(joint).qposadr[0]] = value


def _initial(env, obj: str) -> np.ndarray:
    return env.view.initial_body_pos[env.task.objects[obj].root][0].numpy().copy()


def _point(env, obj: str, point: str) -> np.ndarray:
    return env.view.point_pos(*env.task.objects[obj].points[point])[0].numpy()


def _place_point(env, obj: str, point: str, target, quat=(1.0, 0.0, 0.0, 0.0)) -> None:
    """Pose a free object so that one of its functional points lands on `target`."""
    _set_pose(env, obj, [0, 0, 0], quat)
    _forward(env)
    offset = _point(env, obj, point) - env.view.body_pos(env.task.objects[obj].root)[0].numpy()
    _set_pose(env, obj, np.asarray(target) - offset, quat)


def _forward(env) -> None:
    env.sim.forward(torch.arange(env.num_envs))


def _ok(env) -> bool:
    _forward(env)
    return bool(env.task.success(env.view)[0])


def _lifted(env, obj, dz, quat=(1.0, 0.0, 0.0, 0.0)):
    p = _initial(env, obj)
    _set_pose(env, obj, p + [0, 0, dz], quat)


def test_pickcube():
    env = _fresh("PickCube")
    _lifted(env, "cube", 0.21)
    assert _ok(env)
    _lifted(env, "cube", 0.19)
    assert not _ok(env)


def test_stackcube():
    env = _fresh("StackCube")
    base = env.view.body_pos("base_cube")[0].numpy()
    _set_pose(env, "cube", base + [0.02, 0, 0.05])
    assert _ok(env)
    _set_pose(env, "cube", base + [0.04, 0, 0.05])
    assert not _ok(env), "horizontal offset > 0.035"
    _set_pose(env, "cube", base + [0, 0, 0.08])
    assert not _ok(env), "vertical offset > 0.025"
    _set_pose(env, "cube", base + [0, 0, 0.05])
    adr = env.scene.model.joint("cube/free").dofadr[0]
    env.sim.field("qvel")[0, adr] = 0.2
    assert not _ok(env), "still moving"


@pytest.mark.parametrize("name, obj, point", [("RelocateSphere", "sphere", None),
                                              ("RelocateObject", "bottle", "centre")])
def test_relocate(name, obj, point):
    env = _fresh(name)
    goal = env.view.goal[0].numpy()
    for offset, expected in (([0.02, 0, 0], True), ([0.04, 0, 0], False)):
        if point is None:
            _set_pose(env, obj, goal + offset)
        else:
            _place_point(env, obj, point, goal + offset)
        assert _ok(env) is expected


def test_pickupstick():
    env = _fresh("PickUpStick")
    _lifted(env, "stick", 0.21, _quat_about("x", 20))
    assert _ok(env)
    _lifted(env, "stick", 0.21, _quat_about("x", 40))
    assert not _ok(env), "tilted beyond 30 deg"
    _lifted(env, "stick", 0.15)
    assert not _ok(env), "not lifted enough"


@pytest.mark.parametrize("name, joint, done, not_done", [
    ("TurnOnSwitch", "switch/rocker", 0.85, 0.75),
    ("PushButton", "button/press", 0.85, 0.75),
    ("OpenDrawer", "cabinet/drawer", 0.85, 0.75),
    ("OpenLaptop", "laptop/hinge", 0.72, 0.65),
])
def test_articulation_progress(name, joint, done, not_done):
    env = _fresh(name)
    lo, hi = env.task.joint_range(joint)
    q0 = env.task.initial_joints[joint]
    span = max(q0 - lo, hi - q0)
    direction = 1.0 if hi - q0 >= q0 - lo else -1.0
    for frac, expected in ((done, True), (not_done, False)):
        _set_joint(env, joint, q0 + direction * frac * span)
        assert _ok(env) is expected, (frac, expected)


def test_openfaucet():
    env = _fresh("OpenFaucet")
    q0 = env.task.initial_joints["faucet/handle"]
    _set_joint(env, "faucet/handle", q0 + math.radians(85))
    assert _ok(env)
    _set_joint(env, "faucet/handle", q0 + math.radians(75))
    assert not _ok(env)


def test_grasptwoitems_needs_both_selected_objects_lifted_together():
    env = _fresh("GraspTwoItems")
    on_table = [n for n in env.task.candidates if _initial(env, n)[2] > 0.5]
    assert len(on_table) == 2
    _lifted(env, on_table[0], 0.25)
    assert not _ok(env), "only one lifted"
    _lifted(env, on_table[1], 0.25)
    assert _ok(env)
    _lifted(env, on_table[1], 0.15)
    assert not _ok(env), "second below 0.20"


def _pour_state(env, lift=0.25, tilt=120.0, goal_offset=0.0):
    goal = env.view.goal[0].numpy()
    _place_point(env, "mug", "rim", goal + [goal_offset, 0, 0], _quat_about("y", tilt))
    env.view.initial_body_pos["mug"][0, 2] = goal[2] - lift - 0.05  # reset height below


def test_functional_pour_mug_each_condition():
    env = _fresh("FunctionalPourMug")
    _pour_state(env)
    assert _ok(env)
    _pour_state(env, tilt=80.0)
    assert not _ok(env), "tilt < 100"
    _pour_state(env, goal_offset=0.12)
    assert not _ok(env), "rim too far from goal"
    goal = env.view.goal[0].numpy()
    _place_point(env, "mug", "rim", goal, _quat_about("y", 120.0))
    env.view.initial_body_pos["mug"][0, 2] = goal[2] - 0.1
    assert not _ok(env), "lift < 0.20"
    _pour_state(env)
    _forward(env)
    # A fingertip pressed onto the rim's wall (4 cm from its centre, off the handle).
    rim = _point(env, "mug", "rim") + 0.04 * env.view.axis("mug", (0.0, 1.0, 0.0))[0].numpy()
    tip = env.view.hand_geom_pos()[0, -1].numpy()
    for axis in ("x", "y", "z"):
        _set_joint(env, f"right/wrist/{axis}", float((rim - tip)["xyz".index(axis)]))
    assert not _ok(env), "a hand link touches the rim"


def test_pusht_overlap():
    env = _fresh("PushT")
    gx, gy, gyaw = env.view.goal[0].tolist()
    z = _initial(env, "tee")[2]
    _set_pose(env, "tee", [gx, gy, z], _quat_about("z", math.degrees(gyaw)))
    assert _ok(env) and float(env.task.overlap(env.view)[0]) > 0.99
    _set_pose(env, "tee", [gx, gy, z], _quat_about("z", math.degrees(gyaw) + 25))
    assert not _ok(env), "rotated"
    _set_pose(env, "tee", [gx + 0.03, gy, z], _quat_about("z", math.degrees(gyaw)))
    assert not _ok(env), "shifted"


def test_insertpeg():
    env = _fresh("InsertPeg")
    target = _point(env, "hole", "target")
    bore = env.view.axis(*env.task.objects["hole"].axes["bore"])[0].numpy()
    side = np.cross(bore, [0, 0, 1])
    yaw = math.degrees(math.atan2(-bore[1], -bore[0]))
    quat = _quat_about("z", yaw)
    _place_point(env, "peg", "head", target + 0.01 * bore, quat)
    assert _ok(env)
    _place_point(env, "peg", "head", target + 0.02 * bore, quat)
    assert not _ok(env), "not inserted deep enough"
    _place_point(env, "peg", "head", target + 0.025 * side, quat)
    assert not _ok(env), "outside the bore radius"


def test_bimanual_lift_tray():
    env = _fresh("BimanualLiftTray")
    _lifted(env, "tray", 0.22, _quat_about("x", 8))
    assert _ok(env)
    _lifted(env, "tray", 0.22, _quat_about("x", 12))
    assert not _ok(env), "not level"
    _lifted(env, "tray", 0.15)
    assert not _ok(env), "not lifted"


def test_multigoal_needs_both_at_once():
    env = _fresh("OpenDrawer_RelocateSphere")
    open_q = 0.9 * env.task.joint_range("cabinet/drawer")[1]
    _set_joint(env, "cabinet/drawer", open_q)
    _lifted(env, "sphere", 0.0)
    assert not _ok(env), "primary only"
    _set_joint(env, "cabinet/drawer", 0.0)
    _lifted(env, "sphere", 0.2)
    assert not _ok(env), "add-on only"
    _set_joint(env, "cabinet/drawer", open_q)
    assert _ok(env)


def test_makecoffee_stages_latch_in_order():
    env = _fresh("MakeCoffee")
    task, view = env.task, env.view

    def update():
        _forward(env)
        task.update(view)
        return int(task.completed(view)[0])

    lever_q = task.initial_joints[task.lever] + math.radians(40)
    _set_joint(env, task.lever, lever_q)
    spot = _point(env, "machine", "cup_spot")
    _set_pose(env, "mug", spot)
    assert update() == 0, "later stages do not count before the milk is poured"
    _set_joint(env, task.lever, task.initial_joints[task.lever])
    _set_pose(env, "mug", _initial(env, "mug"))
    _forward(env)
    rim = _point(env, "mug", "rim")
    _place_point(env, "milk", "spout", rim + [0, 0, 0.03], _quat_about("y", 80))
    assert update() == 1
    _set_pose(env, "milk", _initial(env, "milk"))
    assert update() == 1, "a completed stage stays completed"
    _set_pose(env, "mug", spot + [0.05, 0, 0.03])
    assert update() == 2
    assert not task.success(view)[0]
    _set_joint(env, task.lever, lever_q)
    assert update() == 3 and bool(task.success(view)[0])
    assert float(task.state_obs(view)[0, -1]) == 1.0
    env.reset()
    assert int(task.completed(view)[0]) == 0, "reset clears the stage memory"


def test_docs_are_generated_from_the_task_definitions():
    assert docs_path().read_text() == tasks_markdown(), "run `python -m dexbench docs`"
    missing = [name for name in TASKS if not (thumbs_path() / f"{name}.png").is_file()]
    assert not missing, f"no thumbnail for {missing}: run `python -m dexbench docs`"
