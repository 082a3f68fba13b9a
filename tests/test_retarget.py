"""Retargeting human keypoints to each hand, and the keypoint file format.

Each hand retargets "human" keypoints made from its own fingertips at a sequence of poses
(half `power`, full `pinch`, full `tip_pinch`, each settled in simulation, so tendons and
contacts are the model's own, and each at another mount pose), scaled down by its
`RetargetSpec.scale`: every solution must put each fingertip back within 5 mm, the palm
within 1 mm of its pose, and stay within joint and control limits.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from dexbench.embodiments.hands import HANDS
from dexbench.tasks.registry import make_env
from dexbench.teleop.retarget import (
    NUM_KEYPOINTS,
    HandFrame,
    Retargeter,
    robot_as_human,
    wrist_pose,
)
from dexbench.teleop.sources import FileSource, write_keypoints

TIP_TOLERANCE = 0.005  # m
PALM_TOLERANCE = 0.001  # m
SETTLE_STEPS = 500


POSES = (("power", 0.5, (0.05, -0.03, 0.04)), ("pinch", 1.0, (-0.02, 0.06, 0.0)),
         ("tip_pinch", 1.0, (0.0, 0.0, -0.05)))


def reference_pose(retargeter: Retargeter, pose: str, closure: float,
                   shift: tuple[float, float, float]) -> np.ndarray:
    """Settle the robot-only model's hand `closure` of the way from `home` to `pose`
    (implicit integration, as the scenes use), then move the floating mount by `shift`
    (m) and turn it; returns the qpos."""
    model, emb = retargeter.model, retargeter.embodiment
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST  # IK ignores it
    data = mujoco.MjData(model)
    for joint, q in emb.home_qpos.items():
        data.qpos[model.joint(joint).qposadr[0]] = q
    data.ctrl[:] = emb.poses["home"] + closure * (emb.poses[pose] - emb.poses["home"])
    for _ in range(SETTLE_STEPS):
        mujoco.mj_step(model, data)
    if emb.mount == "floating":
        for axis, value in zip(("x", "y", "z", "rz"), (*shift, 0.4 + shift[0]), strict=True):
            data.qpos[model.joint(f"right/wrist/{axis}").qposadr[0]] += value
    else:  # an arm: turn every joint a little (shift's first value, in rad)
        for layout in emb.sides.values():
            for joint in layout.mount_joints:
                data.qpos[model.joint(joint).qposadr[0]] += shift[0]
    return data.qpos.copy()


def human_frame(retargeter: Retargeter, qpos: np.ndarray,
                side: str = "right") -> tuple[HandFrame, np.ndarray]:
    """Keypoints of the robot hand at `qpos` as a human hand `scale` times smaller: tips
    at the mapped indices, other keypoints on the wrist-tip lines; also the tip sites."""
    model, layout = retargeter.model, retargeter.embodiment.sides[side]
    spec = retargeter.embodiment.hand.retarget
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    palm = model.site(layout.palm_site).id
    pos, rot = data.site_xpos[palm], data.site_xmat[palm].reshape(3, 3)
    tips = np.array([data.site_xpos[model.site(s).id] for s in layout.fingertip_sites])
    return robot_as_human(pos, rot, tips, retargeter.wrist[side], spec), tips


@pytest.mark.parametrize("hand", list(HANDS))
def test_retarget_own_fingertips(hand: str) -> None:
    retargeter = Retargeter(f"floating_{hand}")
    model, emb = retargeter.model, retargeter.embodiment
    layout = emb.sides["right"]
    palm = model.site(layout.palm_site).id
    limited = model.jnt_limited.astype(bool)
    adr = model.jnt_qposadr[limited]
    lo, hi = model.jnt_range[limited].T
    for pose, closure, shift in POSES:
        reference = reference_pose(retargeter, pose, closure, shift)
        frame, tips = human_frame(retargeter, reference)
        action = retargeter.retarget({"right": frame})
        err = retargeter.fingertip_error({"right": frame})["right"]
        assert err.max() < TIP_TOLERANCE, f"{hand} {pose}: fingertip errors {err.round(4)} m"

        data = retargeter.configuration.data
        ref = mujoco.MjData(model)
        ref.qpos[:] = reference
        mujoco.mj_kinematics(model, ref)
        assert np.linalg.norm(data.site_xpos[palm] - ref.site_xpos[palm]) < PALM_TOLERANCE
        world = np.array([data.site_xpos[model.site(s).id] for s in layout.fingertip_sites])
        assert np.linalg.norm(world - tips, axis=1).max() < TIP_TOLERANCE + PALM_TOLERANCE

        q = retargeter.configuration.q
        assert np.all(q[adr] >= lo - 1e-6) and np.all(q[adr] <= hi + 1e-6)
        assert action.shape == (len(emb.actuators),)
        assert np.all(action >= emb.ctrl_range[:, 0]) and np.all(action <= emb.ctrl_range[:, 1])


@pytest.mark.parametrize("name", ["fr3_leap", "bimanual_floating_leap"])
def test_retarget_arm_and_bimanual(name: str) -> None:
    """The mount IK places each palm on its wrist target on an arm and on two hands, and
    the targets are laid out as the env's actions."""
    retargeter = Retargeter(name)
    model, emb = retargeter.model, retargeter.embodiment
    env = make_env("BimanualLiftTray" if emb.bimanual else "PickCube", name, num_envs=1,
                   nthread=1)
    assert env.embodiment.actuators == retargeter.actuators
    np.testing.assert_array_equal(env.embodiment.ctrl_range, emb.ctrl_range)
    reference = reference_pose(retargeter, "power", 0.5, (0.05, 0.0, 0.0))
    frames, tips = {}, {}
    for side in emb.sides:
        frames[side], tips[side] = human_frame(retargeter, reference, side)
    retargeter.retarget(frames)
    data = retargeter.configuration.data
    ref = mujoco.MjData(model)
    ref.qpos[:] = reference
    mujoco.mj_kinematics(model, ref)
    for side, err in retargeter.fingertip_error(frames).items():
        assert err.max() < TIP_TOLERANCE, f"{name} {side}: fingertip errors {err.round(4)}"
        palm = model.site(emb.sides[side].palm_site).id
        assert np.linalg.norm(data.site_xpos[palm] - ref.site_xpos[palm]) < PALM_TOLERANCE
        rot = data.site_xmat[palm].reshape(3, 3).T @ ref.site_xmat[palm].reshape(3, 3)
        assert np.arccos(np.clip((np.trace(rot) - 1) / 2, -1, 1)) < 0.01  # rad


@pytest.mark.parametrize("side", ["right", "left"])
def test_wrist_pose_from_keypoints(side: str) -> None:
    """A flat hand (fingers +x, palm down, thumb on the thumb side) turned and moved: the
    wrist pose comes back."""
    sign = -1.0 if side == "right" else 1.0  # y of the thumb side in the wrist frame
    flat = np.zeros((NUM_KEYPOINTS, 3))
    for finger, y in enumerate((-0.04, -0.02, 0.0, 0.02, 0.04)):
        for k in range(4):
            flat[1 + 4 * finger + k] = (0.095 + 0.02 * k, -sign * y, 0.0)
    quat = np.array([0.8, 0.2, -0.4, 0.4])
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat / np.linalg.norm(quat))
    rot = rot.reshape(3, 3)
    moved = flat @ rot.T + np.array([0.1, -0.2, 0.9])
    pose = wrist_pose(moved, side)
    np.testing.assert_allclose(pose[:3, :3], rot, atol=1e-9)
    np.testing.assert_allclose(pose[:3, 3], moved[0], atol=1e-12)


def test_keypoint_file_round_trip(tmp_path) -> None:
    rng = np.random.default_rng(0)
    keypoints = rng.normal(size=(7, 2, NUM_KEYPOINTS, 3))
    wrist = np.tile(np.eye(4), (7, 2, 1, 1))
    wrist[..., :3, 3] = keypoints[:, :, 0]
    path = write_keypoints(tmp_path / "demo.npz", keypoints, wrist, 30.0, ("right", "left"))
    source = FileSource(path)
    assert len(source) == 7 and source.fps == 30.0 and source.handedness == ("right", "left")
    frames = list(source)
    np.testing.assert_array_equal(frames[3]["left"].keypoints, keypoints[3, 1])
    np.testing.assert_array_equal(frames[6]["right"].wrist, wrist[6, 0])
    with pytest.raises(ValueError, match="handedness"):
        write_keypoints(tmp_path / "bad.npz", keypoints, wrist, 30.0, ("right", "right"))
    with pytest.raises(ValueError, match="keypoints"):
        write_keypoints(tmp_path / "bad.npz", keypoints[:, :, :20], wrist, 30.0,
                        ("right", "left"))
