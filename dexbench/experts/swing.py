"""Swing a hinged part open by its handle: hook it, then pull along the hinge's arc.

The grasp-and-move script (`GraspExpert`) hooks the handle; while it carries, its
target is the handle's own position turned a little further about the hinge (so the
pull is tangent to the arc, never out along the door), and the hand's orientation turns
with the part by the angle it has swung since the hook closed. Doors, cupboard and
microwave doors, lids: any hinge, any hand and mount. A latched door's handle (a lever
on its own hinge) is first turned the same way about its own joint, and the hand keeps
it turned (its hook turned with it) while the door swings.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.grasp import GraspExpert, Phase
from dexbench.experts.motion import turned
from dexbench.tasks.plans import SwingPlan

LATCH_LEAD = 0.02  # m of arc the turning handle is led ahead: a short lever's arc bends fast


class SwingExpert(GraspExpert):
    """A `SwingPlan`: a hook grasp whose carry follows the hinge's arc (after turning
    the handle about its own joint, for a latch)."""

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
        self.unlatched = np.full(n, plan.latch is None)  # the handle is turned: swing
        if plan.latch is not None:
            lever = model.joint(plan.latch)
            self._latch = (model.body(lever.bodyid[0]).name, tuple(float(a) for a in lever.pos),
                           tuple(float(a) for a in lever.axis), plan.latch)
            lo, hi = (float(r) for r in lever.range)
            self._latch_limit, self._latch_at = hi, lo + plan.latch_turn * (hi - lo)
            self.latch_from = np.zeros(n)

    def _joint(self, body: str, anchor: tuple[float, ...], axis: tuple[float, ...],
               joint: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(pivot (N, 3), unit axis (N, 3), joint angle (N,)) of a hinge now."""
        view = self.env.view
        return (view.point_pos(body, anchor).cpu().numpy(), view.axis(body, axis).cpu().numpy(),
                view.joint_pos(joint).cpu().numpy())

    def _hinge(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(pivot (N, 3), unit axis (N, 3), joint angle (N,)) of the hinge now."""
        return self._joint(self._hinge_body, self._anchor, self._hinge_axis, self.swing.joint)

    def _turn_latch(self, env: DexEnv, handle: np.ndarray) -> np.ndarray:
        """(N, 3) the hand's goal for the handle while turning the latch: its hook where
        the handle is turned on about the latch's joint by `LATCH_LEAD` of arc (or to
        the stop). The goal is where the hook goes, not a step from where the hand was
        told to be: the hook may slide along the handle, and a hand chasing a short
        arc in steps would slide out along it."""
        pivot, axis, q = self._joint(*self._latch)
        arm = handle - pivot
        radius = np.linalg.norm(arm - (arm * axis).sum(1, keepdims=True) * axis, axis=1)
        angle = np.minimum(LATCH_LEAD / np.maximum(radius, 0.01),
                           np.maximum(self._latch_limit - q, 0.0))
        ahead = pivot + np.einsum("nij,nj->ni", turned(axis, angle), arm)
        return ahead - np.einsum("nij,nj->ni", self.grasp_rot, self.held) - self.pos + handle

    def _ahead(self, env: DexEnv) -> np.ndarray:
        """Where the handle goes next: turned on about the hinge by `lead` of arc (or to
        the limit); with a latch not yet turned, about the latch's joint instead."""
        pivot, axis, q = self._hinge()
        handle = env.view.point_pos(self.body, self.point).cpu().numpy()
        arm = handle - pivot
        radius = np.linalg.norm(arm - (arm * axis).sum(1, keepdims=True) * axis, axis=1)
        left = np.maximum(self.swing.direction * (self._limit - q), 0.0)
        angle = self.swing.direction * np.minimum(self.swing.lead / np.maximum(radius, 0.01),
                                                  left)
        ahead = pivot + np.einsum("nij,nj->ni", turned(axis, angle), arm)
        # The hand turns about its palm: move it so the hook turns about the handle.
        ahead -= np.einsum("nij,nj->ni", self.grasp_rot - self.rot, self.held)
        if self.swing.latch is None:
            return ahead
        return np.where(self.unlatched[:, None], ahead, self._turn_latch(env, handle))

    def act(self) -> torch.Tensor:
        carry = self.phase == Phase.CARRY
        _, axis, q = self._hinge()
        start = carry & ~self.swinging
        self.base[start], self.q_from[start] = self.grasp_rot[start], q[start]
        if self.swing.latch is not None:
            self.unlatched[~carry] = False
            _, latch_axis, latch_q = self._joint(*self._latch)
            self.latch_from[start] = latch_q[start]
            turning = carry & ~self.unlatched
            self.grasp_rot[turning] = (turned(latch_axis, latch_q - self.latch_from)
                                       @ self.base)[turning]
            turned_now = turning & (latch_q >= self._latch_at)
            self.unlatched |= turned_now
            self.base[turned_now] = self.grasp_rot[turned_now]
            self.q_from[turned_now] = q[turned_now]
            carry = carry & self.unlatched
        self.swinging = self.phase == Phase.CARRY
        if carry.any():
            turn = turned(axis, q - self.q_from)
            self.grasp_rot[carry] = (turn @ self.base)[carry]
        return super().act()
