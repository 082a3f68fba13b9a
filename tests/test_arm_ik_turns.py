"""A multi-turn arm joint stalled on the way to its IK target goes the other way round.

The UR10e's wrist 2 followed the warm-started IK from 1.17 to 3.80 rad (GraspPan's palm
turned ~110 deg about the vertical) and stalled at 2.78 rad, the Shadow forearm against
wrist 1; the same pose at 3.80 - 2 pi is a clear turn the other way.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import torch

from dexbench.embodiments.ik import multi_turn, path_blocked
from dexbench.experts.adapter import ActionAdapter, HandCommand
from dexbench.tasks.registry import make_env

# UR10e joints (shoulder pan, shoulder lift, elbow, wrist 1, 2, 3) where GraspPan's arm
# stalled, and the target it stalled short of.
STALLED = np.array([3.41, -0.67, 1.35, -0.68, 2.78, -1.57])
TARGET = np.array([3.41, -0.67, 1.35, -0.68, 3.80, -1.57])


def _arm(env):
    model = env.scene.model
    joints = list(env.embodiment.sides["right"].mount_joints)
    qadr = np.array([model.joint(j).qposadr[0] for j in joints])
    dadr = np.array([model.joint(j).dofadr[0] for j in joints])
    jids = [model.joint(j).id for j in joints]
    act = [next(i for i, a in enumerate(env.embodiment.actuators)
                if model.actuator(a).trntype == mujoco.mjtTrn.mjTRN_JOINT
                and model.actuator(a).trnid[0] == j) for j in jids]
    return model, joints, qadr, dadr, act


def test_multi_turn_joints_are_those_past_a_full_turn():
    """The UR10e's joints but its elbow turn more than 2 pi; a floating wrist's
    rotations (exactly 2 pi) do not, so the floating mount is untouched."""
    env = make_env("GraspPan", "ur10e_shadow", num_envs=1, seed=0, nthread=1)
    model, joints, *_ = _arm(env)
    assert multi_turn(model, joints).tolist() == [True, True, False, True, True, True]
    floating = make_env("PickCube", "floating_shadow", num_envs=1, seed=0, nthread=1)
    layout = floating.embodiment.sides["right"]
    assert not multi_turn(floating.scene.model, list(layout.mount_joints)).any()
    assert not ActionAdapter(floating)._pairs


def test_stalled_wrist_turns_the_other_way_round():
    """With the arm held where it stalled, the adapter's IK target for the palm pose of
    `TARGET` is wrist 2 a full turn the other way, and that pose is the same. (PickCube's
    scene: nothing beside the table lies in the way of the turn; GraspPan's random pan
    may.)"""
    env = make_env("PickCube", "ur10e_shadow", num_envs=1, seed=0, nthread=1)
    env.reset()
    model, _, qadr, dadr, act = _arm(env)
    env.sim.field("qpos")[0, qadr] = torch.as_tensor(STALLED)
    env.sim.field("qvel")[0, dadr] = 0.0
    adapter = ActionAdapter(env)
    adapter.reset(np.arange(1))
    data = mujoco.MjData(model)
    data.qpos[:] = env.sim.field("qpos")[0].numpy()
    data.qpos[qadr] = TARGET
    mujoco.mj_kinematics(model, data)
    site = model.site(env.embodiment.sides["right"].palm_site).id
    pos, rot = data.site_xpos[site].copy(), data.site_xmat[site].reshape(3, 3).copy()
    data.qpos[qadr] = STALLED
    blocked = path_blocked(model, data, qadr, STALLED, TARGET, adapter._pairs["right"])
    assert blocked, "wrist 2 on to 3.80 rad drives the Shadow forearm into wrist 1"
    command = HandCommand(pos[None], rot[None], np.zeros(1))
    for _ in range(20):  # the warm-started IK walks on from where the arm stands
        target = adapter.actions({"right": command}).numpy()[0, act]
    np.testing.assert_allclose(target[4], TARGET[4] - 2 * math.pi, atol=0.05)
    data.qpos[qadr] = target
    mujoco.mj_kinematics(model, data)
    np.testing.assert_allclose(data.site_xpos[site], pos, atol=0.005)
