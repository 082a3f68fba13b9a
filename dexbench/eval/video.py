"""MP4 videos of chosen evaluation episodes, rendered from one camera while they run.

Only the envs running a chosen episode are rendered (one scratch `MjData` filled from
the env's simulator state), so asking for a few videos barely slows a batch of 50.
"""

from __future__ import annotations

import copy
import pathlib

import mujoco
import numpy as np

from dexbench.envs.dex_env import STATE_SPEC, DexEnv
from dexbench.sim.cpu import CpuBackend


class EpisodeCamera:
    """Renders one camera of single envs of a batched `DexEnv`."""

    def __init__(self, env: DexEnv, camera: str, width: int, height: int) -> None:
        model = env.scene.model
        if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
            names = [model.camera(i).name for i in range(model.ncam)]
            raise ValueError(f"no camera {camera!r} for videos; cameras: {', '.join(names)}")
        self._env = env
        self._model = model
        self._renderer = mujoco.Renderer(model, height=height, width=width)
        self._data = mujoco.MjData(model)
        self._world = copy.copy(model)  # per-world colours and lights under visual variation
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._camera.fixedcamid = model.camera(camera).id
        self._option = mujoco.MjvOption()

    def render(self, env_ids: list[int]) -> list[np.ndarray]:
        """(H, W, 3) uint8 frames of those envs in their current state."""
        states = self._env.sim_state()[env_ids].cpu().numpy()
        return [self.render_state(state, env_id)
                for env_id, state in zip(env_ids, states, strict=True)]

    def render_state(self, state: np.ndarray, env_id: int = 0) -> np.ndarray:
        """(H, W, 3) uint8 frame of a recorded simulator state, as env `env_id` shows it
        (its visual variation); the env itself is not touched."""
        mujoco.mj_setState(self._model, self._data, state, STATE_SPEC)
        mujoco.mj_forward(self._model, self._data)
        sim = self._env.sim
        model = (sim.world_model(env_id, self._world) if isinstance(sim, CpuBackend)
                 else self._model)
        mujoco.mjv_updateScene(model, self._data, self._option, None, self._camera,
                               mujoco.mjtCatBit.mjCAT_ALL.value, self._renderer.scene)
        return self._renderer.render().copy()

    def close(self) -> None:
        self._renderer.close()


def write_mp4(frames: list[np.ndarray], path: pathlib.Path, fps: float) -> None:
    """H.264 MP4 of RGB frames, written to a temp file and renamed."""
    import av  # PyAV (from lerobot[dataset]); imported here: runs without videos skip it
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    height, width = frames[0].shape[:2]
    with av.open(str(tmp), mode="w", format="mp4") as container:
        stream = container.add_stream("libx264", rate=round(fps))
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        for frame in frames:
            container.mux(stream.encode(av.VideoFrame.from_ndarray(frame, format="rgb24")))
        container.mux(stream.encode())
    tmp.replace(path)


class EpisodeVideos:
    """Frames of the chosen episodes, per env slot, until each episode ends."""

    def __init__(self, camera: EpisodeCamera, episodes: set[int], out_dir: pathlib.Path,
                 fps: float) -> None:
        self.camera, self.episodes, self.out_dir, self.fps = camera, episodes, out_dir, fps
        self._frames: dict[int, list[np.ndarray]] = {}  # env slot -> frames
        self._episode: dict[int, int] = {}

    def begin(self, slot: int, episode: int) -> None:
        self._frames.pop(slot, None)
        if episode in self.episodes:
            self._frames[slot], self._episode[slot] = [], episode

    def capture(self, slots: list[int] | None = None) -> None:
        """Add the current frame of those recording slots (default: all of them)."""
        slots = sorted(self._frames) if slots is None else [s for s in slots if s in self._frames]
        for slot, frame in zip(slots, self.camera.render(slots), strict=True):
            self._frames[slot].append(frame)

    def end(self, slot: int, success: bool) -> None:
        frames = self._frames.pop(slot, None)
        if frames:
            tag = "success" if success else "failure"
            write_mp4(frames, self.out_dir / f"episode{self._episode[slot]:04d}-{tag}.mp4",
                      self.fps)

    def close(self) -> None:
        self.camera.close()
