"""Where fingers end (`dexbench.experts.surface`) and the pusher that keeps them off the
table: the Inspire hand's finger ends lie 2.7 cm past its fingertip sites (the Shadow
hand's 1.9), so a push at the sites' height pressed them into the table (PushT on the
FR3: 0.15)."""

import mujoco
import numpy as np
import pytest
import torch

from dexbench.envs.dex_env import STATE_SPEC
from dexbench.eval.seeds import eval_keys
from dexbench.experts import make_expert
from dexbench.experts import push as push_module
from dexbench.experts.push import Stage
from dexbench.experts.surface import body_surface
from dexbench.tasks.registry import make_env

SHAPES = """
<mujoco>
  <asset><mesh name="wedge" vertex="0 0 0  0.03 0 0  0 0.02 0  0 0 0.05"/></asset>
  <worldbody>
    <body name="b">
      <geom type="capsule" size="0.01 0.02" pos="0.1 0 0" euler="0 90 0"/>
      <geom type="box" size="0.01 0.02 0.03" pos="0 0.1 0"/>
      <geom type="sphere" size="0.015" pos="0 0 -0.1"/>
      <geom type="cylinder" size="0.02 0.01" pos="-0.1 0 0"/>
      <geom type="mesh" mesh="wedge" pos="0 -0.1 0"/>
      <geom type="sphere" size="0.5" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_body_surface_reaches_each_geoms_far_side():
    model = mujoco.MjModel.from_xml_string(SHAPES)
    points = body_surface(model, model.body("b").id)
    # the capsule lies along x: its far end at 0.1 + 0.02 + 0.01
    assert np.isclose(points[:, 0].max(), 0.13, atol=1e-3)
    assert np.isclose(points[:, 1].max(), 0.12)  # the box's far face
    assert np.isclose(points[:, 2].max(), 0.05)  # the mesh's apex, where the file put it
    assert np.isclose(points[:, 2].min(), -0.115, atol=5e-4)  # the sphere's bottom
    assert np.isclose(points[:, 0].min(), -0.12, atol=1e-3)  # the cylinder's rim
    assert np.isclose(points[:, 1].min(), -0.1, atol=1e-3)  # the mesh's own vertices
    # the large sphere does not collide, so it is no part of the surface
    assert np.linalg.norm(points, axis=1).max() < 0.2


def test_pushing_fingers_do_not_dig_into_the_table():
    """PushT on the FR3 Inspire, episodes 0 and 1: pushing at the fingertip sites'
    height the finger ends sat 1-1.7 mm deep in the table on average (2.8 at most); with
    the ends measured, at most a resting contact's ~1 mm."""
    episodes = [0, 1]
    env = make_env("PushT", "fr3_inspire", num_envs=len(episodes), seed=0, nthread=1)
    env.reset_to(torch.arange(len(episodes)), eval_keys(0, episodes))
    expert = make_expert(env)
    expert.reset(torch.arange(len(episodes)))
    model = env.scene.model
    data = mujoco.MjData(model)
    table = set(np.flatnonzero(model.geom_bodyid == model.body("table").id))
    hand = set(env.scene.hand_geoms)
    depths = []
    for step in range(400):
        env.step(expert.act())
        if step % 5:
            continue
        states = env.sim_state().numpy()
        for i in np.flatnonzero(expert.stage == Stage.PUSH):
            mujoco.mj_setState(model, data, states[i], STATE_SPEC)
            mujoco.mj_forward(model, data)
            dists = [c.dist for c in data.contact[:data.ncon]
                     if {c.geom1, c.geom2} & table and {c.geom1, c.geom2} & hand]
            depths.append(-min(dists, default=0.0))
    assert len(depths) > 40, "the expert pushed"
    assert np.mean(depths) < 0.0005 and max(depths) < 0.0015, (np.mean(depths), max(depths))


def _first_push(embodiment: str):
    env = make_env("PushT", embodiment, num_envs=1, nthread=1)
    expert = make_expert(env)
    env.reset_to(torch.arange(1), eval_keys(0, [0]))
    expert.reset(torch.arange(1))
    expert.act()
    hang = expert._hanging(expert.yaw[:1], expert.tilt[:1], expert.lean[:1])[0]
    site = hang @ expert.offsets[0, expert.lead[0]]
    return expert, hang, site, hang @ expert.aim[0], expert.direction[0]


def test_the_block_pusher_steers_the_leading_fingers_front_not_its_site():
    # LEAP's tip site lies ~2 cm behind its finger's front: the push steers the front
    expert, hang, site, aim, push = _first_push("floating_leap")
    assert (aim - site) @ push > 0.015 and abs(aim[2] - site[2]) < 1e-9
    lo, hi = expert._ends.rows[expert.lead[0]]
    points = expert.surface[0, lo:hi] @ hang.T
    rise = points[:, 2] - site[2] + push_module.LOW + expert.drop[0]
    level = (rise >= 0.0) & (rise <= expert.plan.height)
    front = (points[level] @ push).max()
    assert front - aim @ push == pytest.approx(push_module.TIP_RADIUS, abs=1e-6)
    # the Shadow hand's site is near its finger's front: much the same point
    _, _, site, aim, _ = _first_push("floating_shadow")
    assert np.linalg.norm(aim - site) < 0.004
