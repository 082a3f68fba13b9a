"""How a PPO action becomes the env's joint targets (shared by training and `policy=rl`).

`joints`: one output per actuator, each a delta of its target (`action_scale` x half its
range per control step, from the targets applied last), so exploration noise makes a
random walk rather than jumps across the range.

`synergy`: the mount's actuators (wrist or arm joints) move by deltas as above, while each
hand is commanded by one output per listed synergy: the hand's targets are its `open` pose
plus, for each synergy, a weight in [0, 1] (the output mapped from [-1, 1]) times that
synergy's offset from `open`. Exploring a few grasp weights instead of every finger joint
makes closing the hand around an object a likely event rather than a rare one.
"""

from __future__ import annotations

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv

MODES = ("joints", "synergy")


def delta_targets(prev_targets: torch.Tensor, action: torch.Tensor, low: torch.Tensor,
                  high: torch.Tensor, scale: float) -> torch.Tensor:
    """Joint targets after a delta action of the same width as `low`/`high`."""
    half = (high - low) / 2
    step = scale * half * action.clamp(-1.0, 1.0).to(half.dtype)
    return torch.minimum(torch.maximum(prev_targets.to(half.dtype) + step, low), high)


class ActionMap:
    """PPO actions (N, dim) in [-1, 1] -> joint targets (N, env.action_dim)."""

    def __init__(self, env: DexEnv, mode: str, scale: float,
                 synergies: tuple[str, ...] = ()) -> None:
        if mode not in MODES:
            raise ValueError(f"unknown action mode {mode!r}; modes: {', '.join(MODES)}")
        self.mode, self.scale, self.synergies = mode, scale, tuple(synergies)
        self._low, self._high = env.action_low, env.action_high
        self.device = self._low.device
        actuators = env.embodiment.actuators
        if mode == "joints":
            self.dim = len(actuators)
            return
        poses = env.embodiment.poses
        missing = [s for s in ("open", *self.synergies) if s not in poses]
        if missing or not self.synergies:
            raise ValueError(f"synergy actions need `open` and at least one synergy of "
                             f"{sorted(poses)}; got {list(self.synergies)}")
        emb = env.embodiment
        hands = [emb.hand_actuators(side) for side in sorted(emb.sides)]
        dev, dtype = self._low.device, self._low.dtype
        mount = np.setdiff1d(np.arange(len(actuators)), np.concatenate(hands))
        self._mount = torch.as_tensor(mount, device=dev)
        self._hands = [torch.as_tensor(ids, device=dev) for ids in hands]
        self._open = torch.as_tensor(poses["open"], dtype=dtype, device=dev)
        self._offsets = torch.stack([torch.as_tensor(poses[s], dtype=dtype, device=dev)
                                     - self._open for s in self.synergies])
        self.dim = len(self._mount) + len(hands) * len(self.synergies)

    def targets(self, prev_targets: torch.Tensor, action: torch.Tensor) -> torch.Tensor:
        """The targets to apply, from the targets applied last and the policy's action."""
        if self.mode == "joints":
            return delta_targets(prev_targets, action, self._low, self._high, self.scale)
        prev = prev_targets.to(self._low.dtype)
        action = action.to(self._low.device, self._low.dtype).clamp(-1.0, 1.0)
        out = prev.clone()
        m = self._mount
        out[:, m] = delta_targets(prev[:, m], action[:, :len(m)], self._low[m], self._high[m],
                                  self.scale)
        k = len(self.synergies)
        for j, ids in enumerate(self._hands):
            weights = (action[:, len(m) + j * k:len(m) + (j + 1) * k] + 1.0) / 2.0
            hand = self._open[ids] + weights @ self._offsets[:, ids]
            out[:, ids] = torch.minimum(torch.maximum(hand, self._low[ids]), self._high[ids])
        return out

    def describe(self) -> dict:
        """What `policy.json` records to rebuild this map for the `rl` policy."""
        return {"action_mode": self.mode, "action_scale": self.scale,
                "synergies": list(self.synergies), "action_dim": self.dim}

    @classmethod
    def from_meta(cls, env: DexEnv, meta: dict) -> ActionMap:
        """The map a training run used, from its `policy.json`."""
        return cls(env, meta["action_mode"], float(meta["action_scale"]),
                   tuple(meta["synergies"]))
