"""Teleoperation: a keypoint take recorded as a dataset on another embodiment (validated,
replayed), the source adapters on frames in their own formats, and the transfer
measurement's identity case (the source hand driven by its own commanded motion)."""

from __future__ import annotations

import json
import pathlib
from types import SimpleNamespace

import numpy as np
import pytest

from dexbench.cli.config import ConfigError, runs_root
from dexbench.cli.replay import main as replay_main
from dexbench.cli.teleop import main as teleop_main
from dexbench.data.meta import read_meta
from dexbench.data.validate import validate_dataset
from dexbench.teleop.retarget import wrist_pose
from dexbench.teleop.sources import (
    AVP_TO_MEDIAPIPE,
    FileSource,
    avp_frames,
    mediapipe_frames,
    open_source,
    write_keypoints,
)
from dexbench.teleop.transfer import record_takes, replay_takes


@pytest.fixture(scope="module")
def takes(tmp_path_factory) -> list:
    """Two PickCube expert episodes of the floating Shadow hand as keypoint takes."""
    return record_takes("PickCube", "floating_shadow", 2, 0,
                        tmp_path_factory.mktemp("takes"))


def test_teleop_records_a_dataset_that_validates_and_replays(takes, tmp_path, capsys):
    """The acceptance command, on a take cut to its first 40 frames (kept though it
    fails: keep_failures), on an arm with another hand."""
    full = FileSource(takes[0][1])
    short = write_keypoints(tmp_path / "short.npz", full.keypoints[:40], full.wrist[:40],
                            full.fps, full.handedness)
    out = tmp_path / "ds"
    argv = ["task=PickCube", "embodiment=fr3_leap", f"source=file:{short}", "keep_failures=true",
            "hold_s=0.1", f"out={out}", "progress=false", "sim.nthread=1", "video.every=4"]
    assert teleop_main(argv) == 0
    stats = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert stats["kept"] == 1 and stats["successes"] == 0 and stats["complete"]
    meta = read_meta(out)
    assert meta["embodiment"] == "fr3_leap" and meta["episodes"][0]["success"] is False
    assert meta["episodes"][0]["length"] == 40 + 6  # the take, then 0.1 s held
    assert validate_dataset(out, check_code=False).errors == []
    assert replay_main([f"dataset={out}", "mode=actions", "progress=false",
                        "sim.nthread=1"]) == 0
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert report["max_abs_qpos_error"] == 0.0
    videos = list(runs_root().glob("teleop/*-PickCube/videos/episode0000-failure.mp4"))
    assert videos, "no MP4 of the kept episode"
    # the same command again: the dataset is complete, nothing is recorded
    assert teleop_main(argv) == 0


def test_teleop_bad_input_says_what_to_do(tmp_path):
    with pytest.raises(ConfigError, match="source= is required"):
        teleop_main(["task=PickCube"])
    with pytest.raises(ConfigError, match="num_envs=1"):
        teleop_main(["task=PickCube", "source=file:x.npz", "num_envs=2"])
    with pytest.raises(ConfigError, match="no keypoint file"):
        teleop_main(["task=PickCube", f"source=file:{tmp_path}", f"out={tmp_path / 'ds'}"])
    with pytest.raises(ValueError, match="use file:<path>"):
        open_source("joystick", ("right",))


def test_transfer_identity_solves_and_retargets_exactly(takes):
    """The Shadow hand driven by its own commanded motion solves every take, with
    fingertip errors far below a millimetre."""
    result = replay_takes("PickCube", "floating_shadow", takes, 0)
    assert result.takes == 2 and result.successes == 2
    assert result.tip_error_mm_p95 < 0.5


def _human_hand(rng: np.random.Generator) -> np.ndarray:
    """A plausible right hand, (21, 3) metres: fingers along x from the wrist, thumb to +y."""
    kp = np.zeros((21, 3))
    for finger, y in enumerate((0.04, 0.02, 0.0, -0.02, -0.04)):
        for k in range(4):
            kp[1 + 4 * finger + k] = (0.03 + 0.025 * (k + 1) + (0.02 if finger else -0.03),
                                      y, -0.005 * k)
    return kp + rng.normal(scale=1e-3, size=kp.shape)


def test_avp_frames_map_the_25_joints_in_the_streamers_format():
    """`VisionProStreamer.latest` as the streamer fills it: (1, 4, 4) wrist and (25, 4, 4)
    finger joints relative to it; metacarpals dropped, the rest in MediaPipe order."""
    rng = np.random.default_rng(0)
    hand = _human_hand(rng)
    wrist = np.eye(4)
    wrist[:3, :3] = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # yaw 90
    wrist[:3, 3] = (0.3, 0.1, 1.1)
    fingers = np.repeat(np.eye(4)[None], 25, axis=0)
    for mp, avp in enumerate(AVP_TO_MEDIAPIPE):
        fingers[avp, :3, 3] = hand[mp]
    for metacarpal in (5, 10, 15, 20):
        fingers[metacarpal, :3, 3] = (9.0, 9.0, 9.0)  # must not be used
    latest = {"head": np.eye(4)[None], "right_wrist": wrist[None], "right_fingers": fingers,
              "left_wrist": np.eye(4)[None], "left_fingers": fingers.copy()}
    frame = avp_frames(latest, ("right",))["right"]
    expected = hand @ wrist[:3, :3].T + wrist[:3, 3]
    assert np.allclose(frame.keypoints, expected)
    assert np.allclose(frame.wrist, wrist_pose(expected, "right"))
    with pytest.raises(ValueError, match="25 joint poses"):
        avp_frames({**latest, "right_fingers": fingers[:24]})


def test_mediapipe_frames_from_a_hand_landmarker_result():
    """A `HandLandmarkerResult`-shaped result (landmarks with x, y, z; handedness
    categories): a plain webcam image's "Left" is the operator's right hand, placed by its
    image position, shaped by its world landmarks turned into the scene's axes."""
    rng = np.random.default_rng(1)
    hand = _human_hand(rng)
    # camera axes: x right, y down, z away; the scene's (x, y, z) = (-z, x, -y) of them
    cam = np.column_stack([hand[:, 1], -hand[:, 2], -hand[:, 0]])
    world = [SimpleNamespace(x=p[0], y=p[1], z=p[2]) for p in cam]
    image = [SimpleNamespace(x=0.75, y=0.25, z=0.0)] * 21
    result = SimpleNamespace(handedness=[[SimpleNamespace(category_name="Left")]],
                             hand_world_landmarks=[world], hand_landmarks=[image])
    frame = mediapipe_frames(result)["right"]
    wrist = np.array([0.0, 0.25 * 0.6, 0.25 * 0.4])
    assert np.allclose(frame.keypoints, wrist + hand - hand[0])
    assert "left" in mediapipe_frames(result, mirrored=True)


def test_transfer_command_writes_its_table(capsys):
    from dexbench.cli.introspect import main as dexbench_main

    assert dexbench_main(["transfer", "tasks=[PickCube]", "episodes=1",
                          "targets=[floating_shadow]", "sim.nthread=1"]) == 0
    out = capsys.readouterr().out
    assert "floating_shadow: 1/1 solved" in out
    run_dir = pathlib.Path(json.loads(out.strip().splitlines()[-1])["run_dir"])
    assert "| PickCube | floating_shadow | 1/1 |" in (run_dir / "transfer.md").read_text()
    assert len(json.loads((run_dir / "transfer.json").read_text())["rows"]) == 1


def test_mediapipe_frames_from_mediapipes_own_result_type():
    """The same hand as MediaPipe's own `HandLandmarkerResult` (the `teleop` extra)."""
    pytest.importorskip("mediapipe")
    from mediapipe.tasks.python.components.containers.category import Category
    from mediapipe.tasks.python.components.containers.landmark import Landmark, NormalizedLandmark
    from mediapipe.tasks.python.vision.hand_landmarker import HandLandmarkerResult

    hand = _human_hand(np.random.default_rng(2))
    cam = np.column_stack([hand[:, 1], -hand[:, 2], -hand[:, 0]])
    result = HandLandmarkerResult(
        handedness=[[Category(index=1, score=0.98, display_name="", category_name="Right")]],
        hand_landmarks=[[NormalizedLandmark(x=0.5, y=0.5, z=0.0) for _ in hand]],
        hand_world_landmarks=[[Landmark(x=float(x), y=float(y), z=float(z)) for x, y, z in cam]])
    frames = mediapipe_frames(result)
    assert set(frames) == {"left"}
    assert np.allclose(frames["left"].keypoints, hand - hand[0], atol=1e-6)
