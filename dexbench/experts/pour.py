"""Pouring: hold a vessel by its body, lift it, and tip it over with its rim at a goal.

The grasp-and-carry is `GraspExpert`'s: a side grasp (handshake, thumb up) with the
vessel upright across the palm and the fingers wrapped round it below the rim; the carry
steers the rim, not the palm, to the goal. Once the vessel is clear of the table this
expert turns the held hand about its palm normal, so that the rim swings over towards
the fingertips and the vessel ends up lying in the curled fingers. On the floating
wrist that turn is the innermost hinge alone, so it never runs into the outer hinges'
+-pi stops (a turn about the fingers, palm up, does past 90 degrees).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.base import host_ids
from dexbench.experts.grasp import GraspExpert, GraspPlan, Phase, task_goal
from dexbench.experts.motion import body_yaw, turned


@dataclass(frozen=True)
class PourPlan:
    """`grasp` holds and carries the vessel (its `goal_point`: the rim). Once the hand
    has risen `clearance` (m) it turns, at `turn_rate` (rad/s), by `tilt` (rad) about
    `about` (hand frame; z: the palm normal). The fingers close `squeeze` times as far
    as `grasp.synergy` (within the actuators' ranges: the tipped vessel hangs in them),
    but the actuators matching a regex of `overrides` go to its target instead (fingers
    that would reach over the rim stay out of the way). `grasp_turn` (rad, about `about`
    too) is already there at the grasp: it tips the fingers down (and the forearm up, off
    the table) for a low grasp; `tilt` is the whole turn from the planned side grasp,
    `grasp_turn` included."""

    grasp: GraspPlan
    tilt: float
    clearance: float = 0.05
    turn_rate: float = 1.5
    about: tuple[float, float, float] = (0.0, 0.0, 1.0)
    squeeze: float = 1.0
    overrides: tuple[tuple[str, float], ...] = ()
    grasp_turn: float = 0.0


SQUEEZE = "pour_squeeze"  # the pose name this expert adds to its own adapter


def handle_between(body: str, lo: float, hi: float) -> Callable[[DexEnv], np.ndarray]:
    """Grasp yaw offsets (N,) from `body`'s yaw (its handle along body +x) that put the
    handle between `lo` and `hi` (rad, `lo` < `hi` < `lo` + 2 pi; from the fingers'
    direction towards the palm's facing direction; the handle cannot lie between the
    palm and the vessel), the fingers along world +x where the handle allows it, else
    the nearer end: a hand reaching far round to the side or back towards its own base
    turns the vessel poorly."""
    def offset(env: DexEnv) -> np.ndarray:
        past_lo = (body_yaw(env.view.body_quat(body).cpu().numpy()) - lo) % (2 * np.pi)
        nearer_lo = past_lo - (hi - lo) > 2 * np.pi - past_lo
        rel = np.where(past_lo <= hi - lo, lo + past_lo, np.where(nearer_lo, lo, hi))
        return -rel
    return offset


class PourExpert:
    """`GraspExpert` whose held orientation tips over once the vessel is lifted."""

    def __init__(self, env: DexEnv, plan: PourPlan, side: str = "right") -> None:
        self.plan = plan
        self.grasp = GraspExpert(env, dataclasses.replace(plan.grasp, synergy=SQUEEZE), side)
        self._held_rot = self.grasp.grasp_rot.copy()
        self._angle = np.zeros(env.num_envs)
        self._dt = env.control_dt
        actuators = env.embodiment.actuators
        ranges = env.embodiment.ctrl_range
        # The adapter blends `open` towards a named pose; this expert's adapter gets one more.
        adapter = self.grasp.adapter
        opened, closed = adapter.pose("open"), adapter.pose(plan.grasp.synergy)
        squeezed = np.clip(opened + plan.squeeze * (closed - opened), ranges[:, 0], ranges[:, 1])
        for pattern, target in plan.overrides:
            chosen = np.array([re.search(pattern, a) is not None for a in actuators])
            squeezed = np.where(chosen, target, squeezed)
        adapter.add_pose(SQUEEZE, squeezed)

    @property
    def phase(self) -> np.ndarray:
        return self.grasp.phase

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        self._angle[ids] = 0.0
        self.grasp.reset(env_ids)

    def act(self) -> torch.Tensor:
        grasp = self.grasp
        # A grasp planned on the last step (`GraspExpert` plans on an approach's first
        # step): keep it, and turn what the grasp expert follows away from it.
        planned = (grasp.phase == Phase.APPROACH) & (grasp.timer <= 1.5 * self._dt)
        self._held_rot[planned] = grasp.grasp_rot[planned]
        carry = grasp.phase == Phase.CARRY
        risen = carry & (grasp.pos[:, 2] > grasp.lift_from[:, 2] + self.plan.clearance)
        # Turn gradually: the hanging vessel must not be flung out of the fingers.
        step = self.plan.turn_rate * self._dt
        start = self.plan.grasp_turn
        self._angle = np.where(risen, np.minimum(np.maximum(self._angle, start) + step,
                                                 self.plan.tilt), start)
        axis = self._held_rot @ np.asarray(self.plan.about)
        grasp.grasp_rot[:] = turned(axis, self._angle) @ self._held_rot
        return grasp.act()


# The mug (radius 4 cm, 9.5 cm tall, handle on +x) held low, at 4.5 cm, the palm 1.5 cm
# nearer than for a cube, the fingers tipped 10 degrees down (the forearm would rest on the
# table), its handle anywhere but between the palm and the mug. The fingers close twice
# as hard as the hook synergy (the Shadow hand's fingers are weak); the index finger
# stays open and the thumb swings aside: both would otherwise lie at the rim once the
# mug is tipped and has settled in the hand.
MUG_POUR = PourPlan(
    GraspPlan("mug", point=(0.0, 0.0, 0.045), shift=(-0.01, 0.0, -0.015), yaw="body",
              yaw_offset=handle_between("mug", -0.3, 1.25 * math.pi), side=True,
              synergy="hook", target=task_goal, goal_point=(0.0, 0.0, 0.095)),
    tilt=1.75, turn_rate=0.8, squeeze=2.0, grasp_turn=0.17,
    overrides=((r"FFJ", 0.0), (r"THJ5$", -1.05), (r"THJ4$", 1.22)))


def pour_mug(env: DexEnv) -> PourExpert:
    """The FunctionalPourMug expert."""
    return PourExpert(env, MUG_POUR)
