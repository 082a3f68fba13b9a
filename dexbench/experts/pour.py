"""Pouring: hold a vessel by its body, lift it, and tip it over with its rim at a goal.

The grasp-and-carry is `GraspExpert`'s: a side grasp (handshake, thumb up) with the
vessel upright across the palm and the fingers wrapped round it below the rim; the carry
steers the rim, not the palm, to the goal. Once the vessel is clear of the table this
expert turns the held hand about its palm normal, so that the rim swings over towards
the fingertips and the vessel ends up lying in the curled fingers. On the floating
wrist that turn is the innermost hinge alone, so it never runs into the outer hinges'
+-pi stops (a turn about the fingers, palm up, does past 90 degrees).

The side grasp holds the vessel no lower in the hand than keeps the open fingers (from
the hand's own geometry) above the table, so a broad hand (LEAP) is not stopped by the
table short of the vessel; hands as narrow as the Shadow hand keep their plan. A hand
whose size the plans' body grasp (`hand_shift="vessel"`) does not fit moves it by its own
`HandSpec.shifts["vessel"]` and `vessel_turn` (LEAP's).

A round vessel (`PourPlan.round_body`) may be held from any side: a hand on an arm that
grossly misses the plan's handshake grasp or its pour (the xArm7's reach with the Shadow
forearm pointing up at the end of the pour) takes the grasp turned about the vessel's
axis that the arm's IK reaches best.

On an arm, the links that move as one with the hand (the FR3's link 7, behind the palm of
its flat-mounted hand) may reach below the table at a body grasp low on the vessel: the
link lands on the table and props the hand off the vessel (FR3 with the Wuji hand: palm
3 cm above its pose, only the little finger on the can). The palm then rolls about the
fingers, turned down towards the table, by the least of `ROLLS` that keeps those links
out of it (a hand with its own wrist, the Shadow hand's, bends there instead: no roll).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Sequence

import numpy as np
import torch

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.embodiments.hand_geometry import hand_geometry
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import nearly_best
from dexbench.experts.base import host_ids
from dexbench.experts.grasp import (
    APPROACH_HEIGHT,
    APPROACH_LIFT,
    GraspExpert,
    Phase,
    stand_off,
)
from dexbench.experts.motion import turned, way_poses, yawed
from dexbench.experts.surface import mount_part
from dexbench.tasks.plans import HandleBetween, PourPlan, locate
from dexbench.tasks.predicates import tilt_deg

SQUEEZE = "pour_squeeze"  # the pose name this expert adds to its own adapter
# m the open fingers' geom bounding boxes may reach below the table top: boxes overstate
# round fingers, and the lowest finger of a hand holding a vessel's foot rests on the table.
PRESS = 0.03
# Turns (rad) about a round vessel's vertical axis its grasp may take, tried nearest first.
TURNS = sorted(np.linspace(-np.pi, np.pi, 12, endpoint=False), key=abs)
# The plan's own turn is given up only when that guess misses it by this much (20 cm,
# or 2.5 rad, along the way): the FR3 takes the cup's handshake grasp and pour half the
# time where the guess misses it by up to 9.
GROSS = 10.0
WAYPOINTS = 4  # poses from the hand's to above the grasp that `_turn_round` checks
# Rolls (rad) about the fingers a body grasp may take, palm turned down, least first.
ROLLS = np.linspace(0.0, -0.6, 7)
# m those links may reach below the table top at the planned grasp: the IK, keeping them
# `adapter.TABLE_CLEARANCE` above it, then holds the palm at most 2 cm off its pose, which
# the hook grip takes (the UR10e's and xArm7's grasps of the can, up to 0.7 cm, hold it).
SINK = 0.01


class PourExpert:
    """`GraspExpert` whose held orientation tips over once the vessel is lifted."""

    def __init__(self, env: DexEnv, plan: PourPlan, side: str = "right") -> None:
        self.plan = plan
        # the hand's own shift comes after the table clearance below, so not from here
        self.grasp = GraspExpert(env, dataclasses.replace(
            plan.grasp, synergy=SQUEEZE, standoff=None, hand_shift=None), side)
        self.grasp.offset[1] = max(self.grasp.offset[1], _table_clearance(env, plan, side))
        hand = env.embodiment.hand
        self.grasp.offset += np.asarray(hand.shift_for(plan.grasp.hand_shift))
        # a side grasp round a vessel's body: the hand's `vessel_turn` applies too
        body = plan.grasp.hand_shift == "vessel"
        if plan.grasp.standoff is not None:  # from where the hand clears the table
            self.grasp.offset[2] += stand_off(self.grasp, plan.grasp.standoff)
        self._held_rot = self.grasp.grasp_rot.copy()
        self._up = env.task.objects[plan.grasp.obj].axes.get("up")
        self._angle = np.zeros(env.num_envs)
        self._dt = env.control_dt
        # a floating wrist takes every pose: only an arm's grasp of a round vessel is turned
        self._turn_to_reach = plan.round_body and env.embodiment.mount != "floating"
        actuators = env.embodiment.actuators
        ranges = env.embodiment.ctrl_range
        # The adapter blends `open` towards a named pose; this expert's adapter gets one more.
        adapter = self.grasp.adapter
        opened, closed = adapter.pose("open"), adapter.pose(plan.grasp.synergy)
        squeezed = np.clip(opened + plan.squeeze * (closed - opened), ranges[:, 0], ranges[:, 1])
        self._grasp_turn = plan.grasp_turn + (hand.vessel_turn if body else 0.0)
        self._mount_part = mount_part(env, side) if body else np.zeros((0, 3))
        # the turns `_roll_clear` tries, and the grasp's own turn after them
        self._rolls = turned(np.repeat([[1.0, 0.0, 0.0]], len(ROLLS), axis=0), ROLLS)
        self._at_grasp = turned(np.asarray(plan.about)[None], self._grasp_turn)[0]
        adapter.add_pose(SQUEEZE, _overridden(squeezed, actuators, plan.overrides))
        if plan.open_overrides:
            adapter.add_pose("open", _overridden(opened, actuators, plan.open_overrides))

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
        fresh = np.flatnonzero(planned & (grasp.timer > 0.5 * self._dt))
        if self._turn_to_reach:  # once per plan: `GraspExpert` planned on the last step
            self._turn_round(fresh)
        if len(self._mount_part):
            self._roll_clear(fresh)
        carry = grasp.phase == Phase.CARRY
        risen = carry & (grasp.pos[:, 2] > grasp.lift_from[:, 2] + self.plan.clearance)
        # Turn gradually: the hanging vessel must not be flung out of the fingers.
        step = self.plan.turn_rate * self._dt
        limit = np.full(len(self._angle), self.plan.tilt)
        if self.plan.tip is not None:  # on past `tilt` while the vessel is not tipped
            up = tilt_deg(self.grasp.env.view.axis(*self._up)).cpu().numpy()
            limit = np.where(up < self.plan.tip, self.plan.tilt + self.plan.further,
                             np.maximum(self._angle, self.plan.tilt))
        start = self._grasp_turn
        self._angle = np.where(risen, np.minimum(np.maximum(self._angle, start) + step,
                                                 limit), start)
        axis = self._held_rot @ np.asarray(self.plan.about)
        grasp.grasp_rot[:] = turned(axis, self._angle) @ self._held_rot
        return grasp.act()

    def _turn_round(self, ids: np.ndarray) -> None:
        """Turn the fresh grasps `ids` of a round vessel about the vertical by the least
        of `TURNS` whose way in (from the hand's pose to above the grasp), grasp,
        half-way pour and finished pour (the rim at the target), taken in turn, the
        mount misses within `REACH_MARGIN` of the best (`ActionAdapter.reach_cost`). The
        plan's own turn stays unless missed by `GROSS` or more; an arm's wrist limits may
        forbid it (the handshake grasp of a cup tipped
        115 deg over its fingertips, the Shadow forearm then pointing up). A vessel with a
        handle (its grasp yaw a `HandleBetween`) is turned only where the handle may lie."""
        if not len(ids):
            return
        grasp, plan = self.grasp, self.plan
        point, _ = grasp.object_point(grasp.body, grasp.point)
        rim, _ = grasp.object_point(grasp.goal_body, grasp.goal_point)
        goal = (rim + [0.0, 0.0, plan.grasp.lift] if plan.grasp.target is None
                else np.asarray(plan.grasp.target(grasp.env), dtype=float))
        about = np.asarray(plan.about)
        between = plan.grasp.yaw_offset
        # where a mug's handle lies from the fingers at the plan's own grasp
        handle = -between(grasp.env) if isinstance(between, HandleBetween) else None
        for i in ids:
            held_rots, costs = [], []
            turns = (TURNS if handle is None else
                     [t for t in TURNS if between.clear(handle[i] - t)])
            for turn in turns:
                held = yawed(self._held_rot[i], np.array([turn]))
                axis = held @ about
                at_grasp = (turned(axis, self._grasp_turn) @ held)[0]
                pos = point[i] - at_grasp @ grasp.offset
                rim_in_hand = at_grasp.T @ (rim[i] - pos)
                half = (turned(axis, (self._grasp_turn + plan.tilt) / 2) @ held)[0]
                poured = (turned(axis, plan.tilt) @ held)[0]
                end = goal[i] - poured @ rim_in_hand
                poses = [*self._way_in(i, pos, at_grasp), (pos, at_grasp),
                         ((pos + end) / 2 + [0.0, 0.0, plan.clearance], half), (end, poured)]
                held_rots.append(held[0])
                costs.append(grasp.adapter.reach_cost(grasp.side, i, poses))
                if costs[0] < GROSS:
                    break
            self._held_rot[i] = held_rots[nearly_best(costs)]

    def _roll_clear(self, ids: np.ndarray) -> None:
        """Roll the fresh grasps `ids` about the fingers by the least of `ROLLS` whose
        grasp pose keeps the mount's links that move with the hand no more than `SINK`
        below the table top (the highest of them where none does)."""
        grasp = self.grasp
        point, _ = grasp.object_point(grasp.body, grasp.point)
        for i in ids:
            rots = self._held_rot[i] @ self._rolls @ self._at_grasp
            palm = point[i] - rots @ grasp.offset
            clear = palm[:, 2] + np.einsum("kij,pj->kpi", rots, self._mount_part)[..., 2].min(
                axis=1) - TABLE_TOP_Z
            above = np.flatnonzero(clear >= -SINK)
            self._held_rot[i] = self._held_rot[i] @ self._rolls[above[0] if len(above)
                                                                else int(np.argmax(clear))]

    def _way_in(self, i: int, pos: np.ndarray, rot: np.ndarray
                ) -> list[tuple[np.ndarray, np.ndarray]]:
        """`WAYPOINTS` palm poses from env `i`'s commanded one to above the grasp (`pos`,
        `rot`), evenly apart: the arm's IK follows the way there step by step."""
        grasp = self.grasp
        above = pos - APPROACH_HEIGHT * rot[:, 2]
        above[2] += APPROACH_LIFT * self.plan.grasp.side
        return way_poses(grasp.pos[i], grasp.rot[i], above, rot, WAYPOINTS)


def _overridden(pose: np.ndarray, actuators: Sequence[str],
                overrides: tuple[tuple[str, float], ...]) -> np.ndarray:
    """`pose` with the actuators matching a regex of `overrides` at its target."""
    for pattern, target in overrides:
        chosen = np.array([re.search(pattern, a) is not None for a in actuators])
        pose = np.where(chosen, target, pose)
    return pose


def _table_clearance(env: DexEnv, plan: PourPlan, side: str) -> float:
    """The least hand-frame y of the grasp point that keeps a side grasp's open hand
    (fingers across, thumb up: hand y points down) above the table: a hand whose fingers
    would reach below it stops on the table, away from the vessel it should hold."""
    info = env.task.objects[plan.grasp.obj]
    body, point = locate(env.task.objects, plan.grasp.obj, plan.grasp.point)
    if not plan.grasp.side or body != info.root:
        return -np.inf
    corners = hand_geometry(env.embodiment.hand.name, side).corners
    below = corners[corners[:, 0] > 0.0, 1].max()  # the fingers' lowest reach
    return float(below - PRESS - (info.rest_height + point[2]))
