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

from dexbench.teleop.retarget import NUM_KEYPOINTS, HandFrame

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
