"""Hand frames from a source, retargeted, as the actions of one environment.

`TeleopPlayer` has the experts' interface (`reset`, `act`), so `collect` records
teleoperated episodes exactly as it records scripted ones (actions + simulator states,
resumable, the same dataset format), and adds `ended()`: a recorded take that ran out.

Takes (recorded files) are played at their own frame rate against the control rate (the
frame shown at each control step is the latest one due), episode `j` playing take
`j mod K`; after a take's last frame its last targets are held for `hold_s`, then the
episode ends. A live source (webcam, Vision Pro) gives its latest frame at every control
step and never ends an episode: success or the time limit does. Its frames are in the
operator's space: each episode's first frame is moved (translation only) so that the
first hand's wrist lands where the robot's wrist point is at home.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.teleop.retarget import HandFrame, Retargeter
from dexbench.teleop.sources import FileSource

HOLD_S = 1.0  # s the last frame of a take is held before the episode ends


class LiveSource(Protocol):
    """A source that streams: `latest()` is its newest frame (None before the first)."""

    handedness: tuple[str, ...]

    def latest(self) -> dict[str, HandFrame] | None: ...


class TeleopPlayer:
    """Retargets a source's frames to the actions of a single-env `DexEnv`."""

    def __init__(self, env: DexEnv, source: list[FileSource] | LiveSource,
                 hold_s: float = HOLD_S) -> None:
        if env.num_envs != 1:
            raise ValueError(f"teleoperation drives one environment: num_envs=1, got "
                             f"{env.num_envs}")
        self.env, self.source = env, source
        self.retargeter = Retargeter(env.embodiment.name)
        if tuple(self.retargeter.actuators) != tuple(env.embodiment.actuators):
            raise ValueError("the retargeting model's actuators differ from the env's")
        sides = set(env.embodiment.sides)
        takes = source if isinstance(source, list) else [source]
        for take in takes:
            if not sides <= set(take.handedness):
                raise ValueError(f"{env.embodiment.name} has hands {sorted(sides)}; the source "
                                 f"gives {list(take.handedness)}: record every hand")
        self.hold_steps = round(hold_s / env.control_dt)
        self.episodes = 0  # episodes begun: the next take
        self.step, self.take = 0, None
        self.last: np.ndarray | None = None
        self.offset: np.ndarray | None = None
        self._ended = np.zeros(1, dtype=bool)

    def reset(self, env_ids: torch.Tensor) -> None:
        if isinstance(self.source, list):
            self.take = self.source[self.episodes % len(self.source)]
        self.episodes += 1
        self.step, self.last, self.offset = 0, None, None
        self._ended[:] = False
        self.retargeter.reset()

    def _registered(self, frame: dict[str, HandFrame] | None) -> dict[str, HandFrame] | None:
        """A live frame moved into the scene (the offset fixed by the episode's first)."""
        if frame is None:
            return None
        if self.offset is None:
            side = next(iter(self.env.embodiment.sides))
            r = self.retargeter
            site = r.model.site(r.embodiment.sides[side].palm_site).id
            data = r.configuration.data
            home = data.site_xpos[site] + data.site_xmat[site].reshape(3, 3) @ r.wrist[side]
            self.offset = home - frame[side].keypoints[0]
        moved = {}
        for side, f in frame.items():
            wrist = f.wrist.copy()
            wrist[:3, 3] += self.offset
            moved[side] = HandFrame(f.keypoints + self.offset, wrist)
        return moved

    def _frame(self) -> dict[str, HandFrame] | None:
        if not isinstance(self.source, list):
            return self._registered(self.source.latest())
        t = self._due(self.step)
        return self.take.frame(t) if t < len(self.take) else None

    def _due(self, step: int) -> int:
        """The take's frame due at control step `step`."""
        return math.floor(step * self.env.control_dt * self.take.fps + 1e-9)

    def act(self) -> torch.Tensor:
        frame = self._frame()
        sides = self.env.embodiment.sides
        if frame is not None:
            self.last = self.retargeter.retarget({s: f for s, f in frame.items() if s in sides})
        elif self.last is None:  # nothing seen yet: hold the home pose
            self.last = self.env.home_action.cpu().numpy()
        self.step += 1
        if self.take is not None and self.step >= self._take_steps + self.hold_steps:
            self._ended[:] = True
        return torch.as_tensor(self.last, dtype=torch.float32)[None]

    @property
    def _take_steps(self) -> int:
        """Control steps until every frame of the take has been shown."""
        return math.ceil((len(self.take) - 1e-9) / (self.env.control_dt * self.take.fps))

    def ended(self) -> np.ndarray:
        """(1,) whether a recorded take has run out (and its hold passed)."""
        return self._ended.copy()
