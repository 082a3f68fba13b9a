"""LiftLid and GraspPot: they build and reset with the lid shut, and succeed exactly when
the lid hinge has covered 80% of its opening range (joint state set directly)."""

import math

import pytest
import torch

from dexbench.tasks.registry import make_env

LIDS = [("LiftLid", "box"), ("GraspPot", "pot")]


def _env(name: str):
    env = make_env(name, num_envs=2, seed=0, nthread=1)
    env.reset()
    return env


def _success(env, joint: str, value: float) -> bool:
    env.sim.field("qpos")[0, env.scene.model.joint(joint).qposadr[0]] = value
    env.sim.forward(torch.arange(env.num_envs))
    return bool(env.task.success(env.view)[0])


@pytest.mark.parametrize("name, obj", LIDS)
def test_lid_task_resets_shut_and_succeeds_at_80_percent(name, obj):
    env = _env(name)
    joint = env.task.joint
    lo, hi = env.task.objects[obj].joints[joint]
    assert lo == 0.0 and math.radians(90.0) <= hi <= math.radians(120.0)
    assert env.task.initial_joints[joint] == 0.0
    assert not env.task.success(env.view).any()
    assert _success(env, joint, 0.82 * hi)
    assert not _success(env, joint, 0.78 * hi), "near miss: lid not quite open enough"
    assert not _success(env, joint, 0.0)


@pytest.mark.parametrize("name, obj", LIDS)
def test_lid_stays_shut_under_its_weight(name, obj):
    """No spring: left alone for 1 s the lid rests on its rim and the container on the
    table."""
    env = _env(name)
    action = env.home_action.repeat(env.num_envs, 1)
    for _ in range(60):
        env.step(action)
    q = env.view.joint_pos(env.task.joint)
    assert (q.abs() < 0.01).all()
    assert not env.task.success(env.view).any()
