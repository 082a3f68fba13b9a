"""InsertPen, PushSmallSphereObstacleSlope and BimanualLiftCarton: a state that satisfies
each success predicate and, per clause of the paper's condition, a near miss that does not.
"""

import functools
import math
import re

import numpy as np
import torch

from dexbench.experts.path_push import pointing_pose
from dexbench.tasks.registry import make_env


@functools.cache
def _env(name: str):
    env = make_env(name, num_envs=1, seed=0)
    env.reset()
    return env


def _set_pose(env, obj: str, pos, quat=(1.0, 0.0, 0.0, 0.0)) -> None:
    adr = env.scene.model.joint(env.task.objects[obj].free_joint).qposadr[0]
    env.sim.field("qpos")[0, adr : adr + 7] = torch.tensor([*pos, *quat], dtype=torch.float64)


def _point(env, obj: str, point: str) -> np.ndarray:
    return env.view.point_pos(*env.task.objects[obj].points[point])[0].numpy().copy()


def _ok(env) -> bool:
    env.sim.forward(torch.arange(env.num_envs))
    return bool(env.task.success(env.view)[0])


def _pen_end_at(env, end: str, where) -> None:
    """The pen upright, its end `end` at `where` (the other end straight above it)."""
    half = math.sqrt(0.5)
    down = (half, 0.0, half, 0.0) if end == "tip" else (half, 0.0, -half, 0.0)  # +-90 deg about y
    _set_pose(env, "pen", np.asarray(where) + [0.0, 0.0, 0.07], down)


def test_insert_pen_either_end_centred_and_deep_enough():
    env = _env("InsertPen")
    env.reset()
    rim = _point(env, "holder", "entrance")
    _pen_end_at(env, "tip", rim + [0.01, 0.0, -0.05])
    assert _ok(env)
    assert np.allclose(_point(env, "pen", "tip"), rim + [0.01, 0.0, -0.05], atol=1e-6)
    _pen_end_at(env, "tail", rim + [0.0, 0.02, -0.04])
    assert _ok(env), "either end counts"
    _pen_end_at(env, "tip", rim + [0.0, 0.0, -0.02])
    assert not _ok(env), "only 2 cm below the rim"
    _pen_end_at(env, "tip", rim + [0.045, 0.0, -0.05])
    assert not _ok(env), "off the opening's centre"


def test_push_sphere_obstacle_slope_past_the_line_and_high_enough():
    env = _env("PushSmallSphereObstacleSlope")
    env.reset()
    crest = _point(env, "ramp", "target")
    uphill = env.view.axis(*env.task.objects["ramp"].axes["uphill"])[0].numpy()
    posts = [env.view.body_pos(f"posts{k}")[0].numpy() for k in range(2)]
    foot = _point(env, "ramp", "foot")
    assert all(0 < (p - foot) @ uphill < (crest - foot) @ uphill for p in posts), "on the slope"
    _set_pose(env, "sphere", crest + 0.03 * uphill + [0, 0, 0.02])
    assert _ok(env)
    _set_pose(env, "sphere", crest - 0.01 * uphill + [0, 0, 0.02])
    assert not _ok(env), "not past the line"
    _set_pose(env, "sphere", crest + 0.03 * uphill - [0, 0, 0.01])
    assert not _ok(env), "past the line but below the target's height"
    _set_pose(env, "sphere", foot - 0.05 * uphill + [0, 0, 0.02])
    assert not _ok(env), "at the start"


def test_pointing_pose_opens_only_the_index_chain_and_thumb():
    env = _env("PushSmallSphereObstacleSlope")
    emb = env.embodiment
    pose = pointing_pose(env, "right")
    for a in emb.hand_actuators("right"):
        name = emb.actuators[a]
        kept = "open" if re.search(r"A_(FF|TH|WR)J", name) else "pinch"
        assert pose[a] == emb.poses[kept][a], name
    assert (pose != emb.poses["open"]).any(), "the other fingers curl"


def test_bimanual_lift_carton():
    env = _env("BimanualLiftCarton")
    env.reset()
    start = env.view.initial_body_pos[env.task.objects["carton"].root][0].numpy().copy()
    _set_pose(env, "carton", start + [0, 0, 0.21])
    assert _ok(env)
    _set_pose(env, "carton", start + [0, 0, 0.19])
    assert not _ok(env), "not lifted 0.20 m"
