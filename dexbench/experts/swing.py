"""Swing a hinged part open by its handle: hook it, then pull along the hinge's arc.

The grasp-and-move script (`GraspExpert`) hooks the handle; while it carries, its
target is the handle's own position turned a little further about the hinge (so the
pull is tangent to the arc, never out along the door), and the hand's orientation turns
with the part by the angle it has swung since the hook closed. Doors, cupboard and
microwave doors, lids: any hinge, any hand and mount.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.grasp import GraspExpert, Phase
from dexbench.experts.motion import turned
from dexbench.tasks.plans import SwingPlan


class SwingExpert(GraspExpert):
    """A `SwingPlan`: a hook grasp whose carry follows the hinge's arc."""

    def __init__(self, env: DexEnv, plan: SwingPlan, side: str = "right") -> None:
        grasp = dataclasses.replace(plan.grasp, target=self._ahead,
                                    goal_point=plan.grasp.point, carry_high=False)
        super().__init__(env, grasp, side)
        self.swing = plan
        model = env.scene.model
        joint = model.joint(plan.joint)
        self._hinge_body = model.body(joint.bodyid[0]).name
        self._hinge_axis = tuple(float(a) for a in joint.axis)
        self._anchor = tuple(float(a) for a in joint.pos)
        self._limit = float(joint.range[1] if plan.direction > 0 else joint.range[0])
        n = env.num_envs
        self.base = self.grasp_rot.copy()
        self.q_from = np.zeros(n)
        self.swinging = np.zeros(n, dtype=bool)

    def _hinge(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(pivot (N, 3), unit axis (N, 3), joint angle (N,)) of the hinge now."""
        view = self.env.view
        return (view.point_pos(self._hinge_body, self._anchor).cpu().numpy(),
                view.axis(self._hinge_body, self._hinge_axis).cpu().numpy(),
                view.joint_pos(self.swing.joint).cpu().numpy())

    def _ahead(self, env: DexEnv) -> np.ndarray:
        """Where the handle goes next: turned on about the hinge by `lead` of arc (or to
        the limit)."""
        pivot, axis, q = self._hinge()
        handle = env.view.point_pos(self.body, self.point).cpu().numpy()
        arm = handle - pivot
        radius = np.linalg.norm(arm - (arm * axis).sum(1, keepdims=True) * axis, axis=1)
        left = np.maximum(self.swing.direction * (self._limit - q), 0.0)
        angle = self.swing.direction * np.minimum(self.swing.lead / np.maximum(radius, 0.01),
                                                  left)
        ahead = pivot + np.einsum("nij,nj->ni", turned(axis, angle), arm)
        # The hand turns about its palm: move it so the hook turns about the handle.
        return ahead - np.einsum("nij,nj->ni", self.grasp_rot - self.rot, self.held)

    def act(self) -> torch.Tensor:
        carry = self.phase == Phase.CARRY
        _, axis, q = self._hinge()
        start = carry & ~self.swinging
        self.base[start], self.q_from[start] = self.grasp_rot[start], q[start]
        self.swinging = carry
        if carry.any():
            turn = turned(axis, q - self.q_from)
            self.grasp_rot[carry] = (turn @ self.base)[carry]
        return super().act()
