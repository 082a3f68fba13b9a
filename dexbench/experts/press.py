"""Press: bring the palm or the finger pads above a point of an object and push down.

For buttons, rocker switches and similar: the hand stays open (or in a given synergy),
comes down on the task's functional point and keeps pushing until the task succeeds.
Where the hand touches is measured from the hand itself (palm site or mean fingertip
in the hand frame), so the script serves every hand and mount.
"""

from __future__ import annotations

import numpy as np
import torch

from dexbench.embodiments.ik import rotation_angle
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import ActionAdapter, HandCommand, tips_in_palm_frame
from dexbench.experts.base import host_ids
from dexbench.experts.motion import body_yaw, palm_down, pitch_down, step_towards
from dexbench.tasks.plans import PressPlan, locate

HOVER = 0.08  # m above the point before pressing
PRESS_DEPTH = 0.05  # m the command goes below the point: the push
SPEED = 0.4  # m/s in the air
PRESS_SPEED = 0.08  # m/s while pressing


class PressExpert:
    """Hover over the point, then press down slowly and keep pressing."""

    def __init__(self, env: DexEnv, plan: PressPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        self.body, self.point = locate(env.task.objects, plan.obj, plan.point)
        layout = env.embodiment.sides[side]
        model = env.scene.model
        self._palm = model.site(layout.palm_site).id
        self._tips = [model.site(s).id for s in layout.fingertip_sites]
        n = env.num_envs
        self.pos = np.zeros((n, 3))
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.contact = np.zeros((n, 3))  # pressing point in the hand frame
        self.pressing = np.zeros(n, dtype=bool)

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        if self.plan.with_fingers:
            self.contact[ids] = tips[ids].mean(axis=1)
        else:
            self.contact[ids] = 0.0
        self.pressing[ids] = False
        self.adapter.reset(ids)

    def act(self) -> torch.Tensor:
        view = self.env.view
        body_quat = view.body_quat(self.body).cpu().numpy()
        point = view.point_pos(self.body, self.point).cpu().numpy()
        rot = palm_down(body_yaw(body_quat) + self.plan.yaw) @ pitch_down(self.plan.pitch)
        palm_at_point = point - np.einsum("nij,nj->ni", rot, self.contact)
        hover = palm_at_point + [0.0, 0.0, HOVER]
        arrived = np.linalg.norm(self.pos - hover, axis=1) < 0.01
        self.pressing |= arrived & (np.abs(self._turn(rot)) < 0.05)
        target = np.where(self.pressing[:, None], palm_at_point - [0.0, 0.0, PRESS_DEPTH],
                          hover)
        speed = np.where(self.pressing, PRESS_SPEED, SPEED) * self.env.control_dt
        new_pos, self.rot = step_towards(self.pos, self.rot, target, rot, 1.0,
                                         3.0 * self.env.control_dt)
        step = new_pos - self.pos
        norm = np.maximum(np.linalg.norm(step, axis=1), 1e-9)
        self.pos = self.pos + step * np.minimum(1.0, speed / norm)[:, None]
        closure = np.zeros(self.env.num_envs)
        return self.adapter.actions({self.side: HandCommand(self.pos, self.rot, closure)})

    def _turn(self, target_rot: np.ndarray) -> np.ndarray:
        """Angle (rad) still to turn from the commanded to the target orientation."""
        return rotation_angle(self.rot, target_rot)
