"""Press: bring the palm or the finger pads above a point of an object and push down.

For buttons, rocker switches and similar: the hand stays open (or in a given synergy),
comes down on the task's functional point and keeps pushing until the task succeeds.
Where the hand touches is measured from the hand itself (palm site or mean fingertip
in the hand frame), so the script serves every hand and mount.
"""

from __future__ import annotations

import mujoco
import numpy as np
import torch

from dexbench.embodiments.ik import rotation_angle
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import (
    ActionAdapter,
    HandCommand,
    collidable,
    subtree,
    tips_in_palm_frame,
)
from dexbench.experts.base import host_ids
from dexbench.experts.motion import body_yaw, palm_down, pitch_down, step_towards
from dexbench.tasks.plans import PressPlan, locate

HOVER = 0.08  # m above the point before pressing
PRESS_DEPTH = 0.05  # m the command goes below the point: the push
SPEED = 0.4  # m/s in the air
PRESS_SPEED = 0.08  # m/s while pressing
KEEP_OFF = 0.02  # m every fingertip stays from a `keep_off` part, at the press pose
TURNS = (0.0, np.pi / 2, -np.pi / 2, np.pi)  # rad: the hand's turns tried for `keep_off`


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
        self.weights = np.zeros((n, len(self._tips)))  # fingertips whose mean presses
        self.turn = np.zeros(n)  # rad added to the plan's yaw (`keep_off`)
        self.pressing = np.zeros(n, dtype=bool)
        self._keep_off = []
        if plan.keep_off is not None:
            below = subtree(model, model.body(plan.keep_off).id)
            self._keep_off = [g for b in sorted(below) for g in collidable(model, b)]

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.weights[ids] = 1.0 / len(self._tips)
        self.turn[ids] = 0.0
        if self._keep_off:
            self.turn[ids], self.weights[ids] = self._keep_clear(int(ids[0]), tips[ids[0]])
        if self.plan.with_fingers:
            self.contact[ids] = np.einsum("nk,nki->ni", self.weights[ids], tips[ids])
        else:
            self.contact[ids] = 0.0
        self.pressing[ids] = False
        self.adapter.reset(ids)

    def act(self) -> torch.Tensor:
        view = self.env.view
        body_quat = view.body_quat(self.body).cpu().numpy()
        point = view.point_pos(self.body, self.point).cpu().numpy()
        rot = (palm_down(body_yaw(body_quat) + self.plan.yaw + self.turn)
               @ pitch_down(self.plan.pitch))
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

    def pressing_tips(self) -> np.ndarray:
        """(N, 3) where the fingertips the hand presses with are now (their mean)."""
        tips = self.env.sim.field("site_xpos").cpu().numpy()[:, self._tips]
        return np.einsum("nk,nki->ni", self.weights, tips)

    def _keep_clear(self, env: int, tips: np.ndarray) -> tuple[float, np.ndarray]:
        """(turn, weights of the fingertips pressing) for a just-reset env `env` whose
        fingertips lie at `tips` (hand frame): all of them at the plan's yaw if every tip
        then stays `KEEP_OFF` from the `keep_off` part, else the first of each single
        non-thumb tip, then each turn (`TURNS`), that does; failing all, the clearest."""
        model = self.env.scene.model
        data = mujoco.MjData(model)
        data.qpos[:] = self.env.sim.field("qpos")[env].cpu().numpy()
        mujoco.mj_kinematics(model, data)
        view = self.env.view
        point = view.point_pos(self.body, self.point).cpu().numpy()[env]
        yaw = body_yaw(view.body_quat(self.body).cpu().numpy()[env : env + 1]) + self.plan.yaw
        k = len(tips)
        choices = [np.full(k, 1.0 / k), *np.eye(k)[1:]]  # all tips' mean, each but the thumb
        best = (-np.inf, 0.0, choices[0])
        for turn in TURNS:
            rot = (palm_down(yaw + turn) @ pitch_down(self.plan.pitch))[0]
            for weights in choices:
                world = point + (tips - weights @ tips) @ rot.T
                clear = min(_box_distance(data, g, world).min() for g in self._keep_off)
                if clear >= KEEP_OFF:
                    return turn, weights
                if clear > best[0]:
                    best = (clear, turn, weights)
        return best[1], best[2]

    def _turn(self, target_rot: np.ndarray) -> np.ndarray:
        """Angle (rad) still to turn from the commanded to the target orientation."""
        return rotation_angle(self.rot, target_rot)


def _box_distance(data: mujoco.MjData, geom: int, points: np.ndarray) -> np.ndarray:
    """(k,) distances (m) of world `points` from geom `geom`'s bounding box at `data`'s
    pose: at most their distances from the geom itself, so a clearance errs small."""
    model = data.model
    local = (points - data.geom_xpos[geom]) @ data.geom_xmat[geom].reshape(3, 3)
    centre, half = model.geom_aabb[geom, :3], model.geom_aabb[geom, 3:]
    return np.linalg.norm(np.maximum(np.abs(local - centre) - half, 0.0), axis=-1)
