"""Where human hand frames come from; here, recorded keypoint files.

Keypoint file (`.npz`, written by `write_keypoints`, read by `FileSource`):

- `keypoints` float (T, S, 21, 3): metres, world frame, MediaPipe/MANO order (see
  `dexbench.teleop.retarget`);
- `wrist` float (T, S, 4, 4): each hand's wrist pose, world frame, origin at keypoint 0,
  axes those of the hand frame H (x to the middle knuckle, z out of the palm);
- `handedness` str (S,): the side of each hand, "right" or "left", no repeats;
- `fps` float: frames per second of the recording;
- `version` int: 1.

T frames, S hands (1, or 2 for bimanual embodiments).
"""

from __future__ import annotations

import pathlib
from collections.abc import Iterator

import numpy as np

from dexbench.teleop.retarget import NUM_KEYPOINTS, HandFrame, wrist_pose

FORMAT_VERSION = 1
SIDES = ("right", "left")


def _check(keypoints: np.ndarray, wrist: np.ndarray, handedness: tuple[str, ...]) -> None:
    """Shapes and sides of a keypoint recording, with the fix in each message."""
    n, s = keypoints.shape[:2] if keypoints.ndim == 4 else (0, 0)
    if keypoints.shape != (n, s, NUM_KEYPOINTS, 3) or n == 0:
        raise ValueError(f"keypoints must be (T, S, {NUM_KEYPOINTS}, 3) with T > 0, "
                         f"got {keypoints.shape}")
    if wrist.shape != (n, s, 4, 4):
        raise ValueError(f"wrist must be (T, S, 4, 4) = {(n, s, 4, 4)}, got {wrist.shape}")
    if len(handedness) != s or len(set(handedness)) != s or not set(handedness) <= set(SIDES):
        raise ValueError(f"handedness must name each of the {s} hands once from {SIDES}, "
                         f"got {handedness}")


def write_keypoints(path: str | pathlib.Path, keypoints: np.ndarray, wrist: np.ndarray,
                    fps: float, handedness: tuple[str, ...] = ("right",)) -> pathlib.Path:
    """Write a keypoint file (format above); returns its path."""
    keypoints, wrist = np.asarray(keypoints, float), np.asarray(wrist, float)
    _check(keypoints, wrist, tuple(handedness))
    path = pathlib.Path(path)
    np.savez_compressed(path, keypoints=keypoints, wrist=wrist, fps=float(fps),
                        handedness=np.array(handedness), version=FORMAT_VERSION)
    return path


class FileSource:
    """Frames of a recorded keypoint file, in order, at its own rate."""

    def __init__(self, path: str | pathlib.Path) -> None:
        with np.load(path) as f:
            version = int(f["version"]) if "version" in f else None
            if version != FORMAT_VERSION:
                raise ValueError(f"{path}: keypoint file version {version}, this reader "
                                 f"reads {FORMAT_VERSION} (see dexbench.teleop.sources)")
            self.keypoints = f["keypoints"].astype(float)
            self.wrist = f["wrist"].astype(float)
            self.fps = float(f["fps"])
            self.handedness = tuple(str(h) for h in f["handedness"])
        _check(self.keypoints, self.wrist, self.handedness)

    def __len__(self) -> int:
        return len(self.keypoints)

    def frame(self, t: int) -> dict[str, HandFrame]:
        """Frame `t`: one `HandFrame` per side."""
        return {side: HandFrame(self.keypoints[t, i], self.wrist[t, i])
                for i, side in enumerate(self.handedness)}

    def __iter__(self) -> Iterator[dict[str, HandFrame]]:
        return (self.frame(t) for t in range(len(self)))


# Apple Vision Pro (`avp_stream.VisionProStreamer.latest`): per hand a wrist pose
# `<side>_wrist` (1, 4, 4) in the headset's world frame (z up) and 25 joint poses
# `<side>_fingers` (25, 4, 4) in the wrist's frame, ARKit order: 0 wrist; thumb 1-4
# (knuckle .. tip); index, middle, ring, little 5-9, 10-14, 15-19, 20-24 (metacarpal,
# knuckle, intermediate base, intermediate tip, tip). The metacarpals (5, 10, 15, 20)
# have no MediaPipe keypoint; the rest map in order:
AVP_TO_MEDIAPIPE = (0, 1, 2, 3, 4, 6, 7, 8, 9, 11, 12, 13, 14, 16, 17, 18, 19, 21, 22, 23, 24)


def avp_frames(latest: dict, sides: tuple[str, ...] = ("right",)) -> dict[str, HandFrame]:
    """Hand frames from one `VisionProStreamer.latest` dict (its world frame; the wrist
    frame is rebuilt from the keypoints, ARKit's wrist axes being another convention)."""
    frames = {}
    for side in sides:
        joints = np.asarray(latest[f"{side}_wrist"], float)[0] @ np.asarray(
            latest[f"{side}_fingers"], float)
        if joints.shape != (25, 4, 4):
            raise ValueError(f"{side}_fingers must hold 25 joint poses, got {joints.shape[0]}")
        keypoints = joints[list(AVP_TO_MEDIAPIPE), :3, 3]
        frames[side] = HandFrame(keypoints, wrist_pose(keypoints, side))
    return frames


# MediaPipe Hands (`HandLandmarkerResult`): per detected hand `hand_world_landmarks`
# (21 landmarks x, y, z in metres, origin near the hand's centre, camera axes: x right,
# y down, z away from the camera), `hand_landmarks` (normalised image x, y) and
# `handedness` (a category named "Left" or "Right", as seen in a mirrored, selfie image).
# A webcam facing the operator: the scene's x (away from the robot) is towards the
# camera, its y (left) the image's right, its z up.
CAMERA_TO_SCENE = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
WORKSPACE = (0.6, 0.4)  # m of scene (y, z) the image's width and height span


def mediapipe_frames(result, mirrored: bool = False) -> dict[str, HandFrame]:
    """Hand frames from one MediaPipe `HandLandmarkerResult`, in an operator frame whose
    origin is the image centre: the wrist placed by its image position over `WORKSPACE`,
    the hand's shape from the world landmarks. `mirrored`: the image is a selfie view
    (MediaPipe's own handedness assumption); a plain webcam image swaps the labels."""
    frames = {}
    for cats, world, image in zip(result.handedness, result.hand_world_landmarks,
                                  result.hand_landmarks, strict=True):
        label = cats[0].category_name.lower()
        side = label if mirrored else {"left": "right", "right": "left"}[label]
        local = np.array([[p.x, p.y, p.z] for p in world], float)
        if local.shape != (NUM_KEYPOINTS, 3):
            raise ValueError(f"a MediaPipe hand has {NUM_KEYPOINTS} landmarks, got "
                             f"{len(local)}")
        wrist = np.array([0.0, (image[0].x - 0.5) * WORKSPACE[0],
                          (0.5 - image[0].y) * WORKSPACE[1]])
        keypoints = wrist + (local - local[0]) @ CAMERA_TO_SCENE.T
        frames[side] = HandFrame(keypoints, wrist_pose(keypoints, side))
    return frames


class VisionProSource:
    """Apple Vision Pro hand tracking through `avp_stream` (pip install avp_stream)."""

    def __init__(self, ip: str, sides: tuple[str, ...] = ("right",)) -> None:
        from avp_stream import VisionProStreamer  # optional: only for this source

        self.handedness = sides
        self.streamer = VisionProStreamer(ip=ip, record=False)

    def latest(self) -> dict[str, HandFrame] | None:
        latest = self.streamer.latest
        return None if latest is None else avp_frames(latest, self.handedness)


LANDMARKER_MODEL = "hand_landmarker.task"


class WebcamSource:
    """A webcam through MediaPipe's hand landmarker (the `teleop` extra; the model file
    `hand_landmarker.task` from MediaPipe's model page, at `$DEXBENCH_HAND_LANDMARKER` or
    `~/.cache/dexbench/hand_landmarker.task`)."""

    def __init__(self, index: int = 0, sides: tuple[str, ...] = ("right",)) -> None:
        import os

        import cv2
        from mediapipe.tasks.python import BaseOptions, vision

        model = pathlib.Path(os.environ.get(
            "DEXBENCH_HAND_LANDMARKER", pathlib.Path.home() / ".cache/dexbench" / LANDMARKER_MODEL))
        if not model.exists():
            raise FileNotFoundError(f"no MediaPipe hand landmarker model at {model}: download "
                                    f"{LANDMARKER_MODEL} there or set DEXBENCH_HAND_LANDMARKER")
        options = vision.HandLandmarkerOptions(
            base_options=BaseOptions(model_asset_path=str(model)), num_hands=len(sides),
            running_mode=vision.RunningMode.VIDEO)
        self.detector = vision.HandLandmarker.create_from_options(options)
        self.camera, self.cv2 = cv2.VideoCapture(index), cv2
        self.handedness, self.frames = sides, 0

    def latest(self) -> dict[str, HandFrame] | None:
        import mediapipe

        ok, bgr = self.camera.read()
        if not ok:
            return None
        image = mediapipe.Image(image_format=mediapipe.ImageFormat.SRGB,
                                data=self.cv2.cvtColor(bgr, self.cv2.COLOR_BGR2RGB))
        self.frames += 1
        result = self.detector.detect_for_video(image, self.frames * 33)
        frames = mediapipe_frames(result)
        return frames if set(self.handedness) <= set(frames) else None


def open_source(spec: str, sides: tuple[str, ...]) -> list[FileSource] | object:
    """`file:<keypoint file or folder of them>` (takes, in name order), `webcam[:<index>]`
    or `avp:<ip>`."""
    kind, _, arg = spec.partition(":")
    if kind == "file":
        path = pathlib.Path(arg)
        files = sorted(path.glob("*.npz")) if path.is_dir() else [path]
        if not files or not all(f.is_file() for f in files):
            raise FileNotFoundError(f"source={spec}: no keypoint file (.npz) at {path}")
        return [FileSource(f) for f in files]
    if kind == "webcam":
        return WebcamSource(int(arg or 0), sides)
    if kind == "avp" and arg:
        return VisionProSource(arg, sides)
    raise ValueError(f"source={spec}: use file:<path>, webcam[:<index>] or avp:<ip>")
