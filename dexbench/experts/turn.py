"""Turn a hinged part: push its tip around its hinge with the fingers.

For faucet levers (vertical hinge: the hand hangs its fingers beside the lever tip, pads
facing the way the tip must go) and lids (horizontal hinge: palm-down fingers, tilted
down, slide under the free edge). Either way the fingers keep a little ahead of the tip
along its arc until the task succeeds. The contact point is measured on the hand itself
(mean fingertip), so the script serves every hand and mount.
"""

from __future__ import annotations

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import (
    ActionAdapter,
    HandCommand,
    palm_and_finger_sites,
    tips_in_palm_frame,
)
from dexbench.experts.base import host_ids
from dexbench.experts.motion import body_yaw, palm_down, pitch_down, step_towards
from dexbench.tasks.plans import TurnPlan, locate

SPEED = 0.4  # m/s in the air
PUSH_SPEED = 0.1  # m/s along the arc
HOVER = 0.08  # m above the lever before going down beside it
LEAD = 0.03  # m the pads aim ahead of the tip along the arc
BESIDE = 0.025  # m the pads start behind the tip, on the side they push from


class TurnExpert:
    """Go down beside the lever tip, then push it along its arc."""

    def __init__(self, env: DexEnv, plan: TurnPlan, side: str = "right") -> None:
        self.env, self.plan, self.side = env, plan, side
        self.adapter = ActionAdapter(env)
        model = env.scene.model
        self._palm, self._tips = palm_and_finger_sites(env, side)
        info = env.task.objects[plan.obj]
        self.body, self.tip = locate(env.task.objects, plan.obj, plan.tip)
        self.frame = info.root
        hinge = plan.hinge or next(iter(info.joints))
        self._hinge_body = model.body(model.joint(hinge).bodyid[0]).name
        self._hinge_axis = tuple(model.joint(hinge).axis)
        n = env.num_envs
        self.pos = np.zeros((n, 3))
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.pads = np.zeros((n, 3))  # finger pads in the hand frame
        self.stage = np.zeros(n, dtype=np.int64)  # 0 hover, 1 down beside, 2 push

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.pads[ids] = tips[ids].mean(axis=1)
        self.stage[ids] = 0
        self.adapter.reset(ids)

    def act(self) -> torch.Tensor:
        view = self.env.view
        tip = view.point_pos(self.body, self.tip).cpu().numpy()
        pivot = view.body_pos(self._hinge_body).cpu().numpy()
        axis = view.axis(self._hinge_body, self._hinge_axis).cpu().numpy()
        radial = tip - pivot
        radial -= (radial * axis).sum(axis=1, keepdims=True) * axis
        radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-9)
        tangent = self.plan.direction * np.cross(axis, radial)
        if self.plan.pitch is None:
            # Fingers hanging, pads (palm side) facing the push direction.
            yaw = np.arctan2(-tangent[:, 1], -tangent[:, 0])
            rot = palm_down(yaw) @ pitch_down(np.pi / 2)
            approach = np.array([0.0, 0.0, 1.0])
        else:
            rot = palm_down(body_yaw(view.body_quat(self.frame).cpu().numpy())) @ pitch_down(
                self.plan.pitch)
            approach = view.axis(self.frame, self.plan.approach).cpu().numpy()
        beside = tip - BESIDE * tangent
        ahead = tip + LEAD * tangent
        pads_world = np.einsum("nij,nj->ni", rot, self.pads)
        goal = {0: beside + HOVER * approach, 1: beside, 2: ahead}
        target = np.stack([goal[int(s)][i] for i, s in enumerate(self.stage)]) - pads_world
        close = np.linalg.norm(self.pos - target, axis=1) < 0.01
        self.stage[(self.stage < 2) & close] += 1
        speed = np.where(self.stage == 2, PUSH_SPEED, SPEED)[:, None] * self.env.control_dt
        self.pos, self.rot = step_towards(self.pos, self.rot, target, rot, speed,
                                          3.0 * self.env.control_dt)
        closure = np.zeros(self.env.num_envs)
        return self.adapter.actions({self.side: HandCommand(self.pos, self.rot, closure)})
