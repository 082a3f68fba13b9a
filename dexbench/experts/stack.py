"""Stack and lift (`StackLiftPlan`): stack one item on the other, then lift the stack
in one side grasp.

No single grasp holds two of the shapes lying side by side or in line: the fingers
squeeze against the thumb along one axis, so the second item has nothing opposing it.
Stacked, the top item rests on the bottom one and the hand only grips the bottom item:
from the side, rolled so the thumb is underneath and the palm faces the stack, the thumb
and index finger hold the base while the upper fingers and the palm fence in the top
item. The script picks up the item that makes the worse base with a top-down power or
pinch grasp, sets it on the other one (turned so that a long item lies across the final
grasp), lets go, rolls the hand, grips the stack's base and lifts. Whatever falls, the
env opens, backs off and starts over from the items where they are.

Known weak spots (floating Shadow hand, 16 envs each of seeds 0-5: 75/96 stacks lifted):
the ball and capsule pair has no base at all (a lying capsule holds nothing and nothing
stays on the ball); a prism or box set on the standing cylinder, or a prism on the box,
sometimes falls off while the hand comes round for the side grasp.
"""

from __future__ import annotations

from enum import IntEnum

import mujoco
import numpy as np
import torch

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.embodiments.hand_geometry import thumb_actuators
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import ActionAdapter, HandCommand, site_pose
from dexbench.experts.base import host_ids, phase_machine_state
from dexbench.experts.motion import (
    TRAVEL_RISE,
    body_yaw,
    palm_down,
    step_towards,
    via_travel,
    wrap,
    yawed,
)
from dexbench.tasks.plans import StackLiftPlan


class Stage(IntEnum):
    REACH = 0  # above the top item's grasp pose (via the travel height), hand open
    DESCEND = 1  # down onto it
    CLOSE = 2  # close the item's synergy
    CARRY = 3  # lift it over the base and lower it onto the base
    RELEASE = 4  # open, back off upwards; then check the stack
    RISE = 5  # straight up, clear of the stack, before rolling the hand
    TURN = 6  # roll into the side pose above the side grasp's approach point
    LOWER = 7  # down beside the stack
    ENTER = 8  # in, the palm towards the stack
    GRIP = 9  # close on the base
    LIFT = 10  # both items up
    DROP = 11  # something fell: open, back off, start over


# Side grasp of the stack's base: the top-down grasp rolled about the fingers by
# SIDE_ROLL (rad) so the thumb side goes down, the base held SIDE_SHIFT (hand frame)
# towards the index finger from the top-down cube grasp and the hand SIDE_RISE higher,
# so the thumb and palm edge clear the table while the upper fingers reach the top item.
SIDE_ROLL = 1.4
SIDE_SHIFT = (0.0, -0.02, 0.0)
SIDE_RISE = 0.01
APPROACH_HEIGHT = 0.10  # m behind the palm of a grasp pose
SPEED = 0.45  # m/s in free space
CAREFUL_SPEED = 0.2  # m/s onto an item and carrying it
LIFT_SPEED = 0.15  # m/s lifting the stack: well under the task's 0.5 m/s
TURN_RATE = 3.0  # rad/s
ARRIVED = 0.008  # m: the palm this close to a grasp pose starts the closing
PAUSE_SECONDS = 0.2
CLOSE_SECONDS = 0.5
SETTLE_SECONDS = 1.0
LOST_DISTANCE = 0.05  # m: the carried item this far from where the hand holds it: drop
CARRY_CLEARANCE = 0.04  # m the carried item's bottom clears the base's top travelling
# The held item is pressed PLACE_PRESS into the base, which seats it, so it is let go
# once it is within PLACE_NEAR of that goal after PLACE_TIMEOUT (or within
# PLACE_TOLERANCE sooner).
PLACE_PRESS = 0.004  # m
PLACE_TOLERANCE = 0.006  # m
PLACE_NEAR = 0.015  # m
PLACE_TIMEOUT = 1.0  # s
OPEN_SECONDS = 0.4
LET_GO_SECONDS = 1.2  # opening slowly on the base: a quick one flicks the item off
RELEASE_SLIDE = 0.02  # m the hand slides back (against the fingers) while they open
BACK_OFF = 0.06  # m the open hand withdraws
STACKED_XY = 0.025  # m: the top item's centre this near the base's axis is stacked
LIFT_HEIGHT = 0.30  # m the stack is lifted
LIFT_CHECK = 0.08  # m: once the hand rose this far, both items must have come along
LIFTED = 0.03  # m above its rest height an item counts as coming along


class StackLiftExpert:
    """Stack-and-lift phase machine for the right hand (GraspTwoItems)."""

    def __init__(self, env: DexEnv, plan: StackLiftPlan, side: str = "right") -> None:
        self.env, self.side = env, side
        self.adapter = ActionAdapter(env)
        self.items = plan.items
        hand = env.embodiment.hand
        self.offset = np.asarray(hand.grasp_offset)
        self.names = list(plan.candidates)
        self.rest = np.array([env.task.objects[n].rest_height for n in self.names])
        model = env.scene.model
        self._palm_site = model.site(env.embodiment.sides[side].palm_site).id
        self._dt = env.control_dt
        emb = env.embodiment
        self._hand = emb.hand_actuators(side)
        self._open = emb.poses["open"][self._hand]
        self._power = emb.poses["power"][self._hand]
        self._closed = {name: emb.poses[self.items[name].synergy][self._hand]
                        for name in self.names}
        self._ready = self._open.copy()
        layout = emb.sides[side]
        self._thumb = thumb_actuators(model, model.site(layout.palm_site).bodyid[0],
                                      model.site(layout.fingertip_sites[0]).bodyid[0])[self._hand]
        low, high = emb.ctrl_range[self._hand].T
        for k, i in enumerate(self._hand):
            name = emb.actuators[i].rsplit("_", 2)[-2:]
            target = plan.side_ready.get(hand.name, {}).get("_".join(name))
            if target is not None:
                self._ready[k] = np.clip(target, low[k], high[k])
        bodies = [model.body(env.task.objects[name].root).id for name in self.names]
        self._geoms = [np.flatnonzero(model.geom_bodyid == b) for b in bodies]
        n = env.num_envs
        self.stage, self.timer, self.closure, self.pos, self.rot = phase_machine_state(n)
        self.grasp_pos = np.zeros((n, 3))
        self.grasp_rot = self.rot.copy()
        self.held = np.zeros((n, 3))
        self.travel_z = np.zeros(n)
        self.turn = np.zeros(n)  # yaw the hand turns while carrying, to line the items up
        self.lift_from = np.zeros((n, 3))
        self.let_go_from = np.zeros((n, 3))
        self.top = np.zeros(n, dtype=np.int64)
        self.base = np.zeros(n, dtype=np.int64)

    def _palm(self) -> tuple[np.ndarray, np.ndarray]:
        return site_pose(self.env, self._palm_site)

    def _items(self) -> tuple[np.ndarray, np.ndarray]:
        """(N, 5, 3) positions and (N, 5) yaws of every candidate shape."""
        view = self.env.view
        pos = np.stack([view.body_pos(n).cpu().numpy() for n in self.names], axis=1)
        yaw = np.stack([body_yaw(view.body_quat(n).cpu().numpy()) for n in self.names], 1)
        return pos, yaw

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot = self._palm()
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.stage[ids], self.timer[ids], self.closure[ids] = Stage.REACH, 0.0, 0.0
        self.adapter.reset(ids)

    def _choose(self, ids: np.ndarray, items: np.ndarray) -> None:
        """The two shapes on the table (nearest its centre); the better base stays put."""
        near = np.argsort(np.linalg.norm(items[:, :, :2], axis=2), axis=1)[:, :2]
        rank = np.array([99 if self.items[n].base is None else self.items[n].base
                         for n in self.names])
        first_is_base = rank[near[:, 0]] <= rank[near[:, 1]]
        self.base[ids] = np.where(first_is_base, near[:, 0], near[:, 1])[ids]
        self.top[ids] = np.where(first_is_base, near[:, 1], near[:, 0])[ids]

    def _heading(self, shape: np.ndarray, yaw: np.ndarray,
                 toward: np.ndarray | None = None) -> np.ndarray:
        """(N,) finger yaw for grasping shapes (N,) (indices) lying at yaws (N,): of the
        yaws their symmetry allows, the one nearest `toward` (N,) (default 0)."""
        out = np.zeros(len(shape)) if toward is None else toward.copy()
        for k, name in enumerate(self.names):
            item, mine = self.items[name], shape == k
            fold = {"box": np.pi / 2, "body": np.pi}.get(item.yaw)
            if fold is not None:
                base = yaw[mine] + item.yaw_offset
                out[mine] = base + fold * np.round(wrap(out[mine] - base) / fold)
        return wrap(out)

    def _pick_pose(self, i: int, items: np.ndarray, yaws: np.ndarray, turn: bool) -> None:
        """Grasp pose of env i's top item; its yaw is planned if `turn`, else kept."""
        item = self.items[self.names[self.top[i]]]
        yaw = yaws[i, self.top[i]]
        if turn:
            # Fingers towards the base: the forearm then stays clear of it.
            away = items[i, self.base[i]] - items[i, self.top[i]]
            heading = self._heading(self.top[i:i + 1], yaws[i:i + 1, self.top[i]],
                                    np.arctan2(away[1:2], away[0:1]))
            self.grasp_rot[i] = palm_down(heading)[0]
        point = items[i, self.top[i]] + yawed(np.eye(3), np.array([yaw]))[0] @ item.point
        self.grasp_pos[i] = point - self.grasp_rot[i] @ (self.offset + np.asarray(item.shift))

    def _side_yaw(self, yaws: np.ndarray) -> np.ndarray:
        """(N,) finger yaw of the stack's side grasp: square to its base's faces."""
        return self._heading(self.base, yaws[np.arange(len(yaws)), self.base])

    def act(self) -> torch.Tensor:
        items, yaws = self._items()
        n = len(items)
        rows = np.arange(n)
        self.timer += self._dt
        stage = self.stage
        palm, palm_rot = self._palm()
        target_pos, target_rot = self.pos.copy(), self.rot.copy()

        fresh = (stage == Stage.REACH) & (self.timer <= self._dt)
        if fresh.any():
            self._choose(np.flatnonzero(fresh), items)
        for i in np.flatnonzero(stage <= Stage.DESCEND):
            self._pick_pose(i, items, yaws, bool(fresh[i]))
        above = self.grasp_pos - APPROACH_HEIGHT * self.grasp_rot[:, :, 2]
        self.travel_z[fresh] = np.maximum(above[:, 2], self.pos[:, 2] + TRAVEL_RISE)[fresh]

        reach = stage == Stage.REACH
        waypoint, low = via_travel(self.pos, above, self.travel_z)
        target_pos[reach] = waypoint[reach]
        target_rot[reach & ~low] = self.grasp_rot[reach & ~low]
        near = np.linalg.norm(self.pos - above, axis=1) < 0.01
        self._advance(reach & ((near & (self.timer > 0.3)) | (self.timer > 4.0)),
                      Stage.DESCEND)

        descend = stage == Stage.DESCEND
        target_pos[descend], target_rot[descend] = (self.grasp_pos[descend],
                                                    self.grasp_rot[descend])
        arrived = ((np.linalg.norm(self.pos - self.grasp_pos, axis=1) < 0.005)
                   & (np.linalg.norm(palm - self.grasp_pos, axis=1) < ARRIVED))
        self._advance(descend & (arrived | (self.timer > 2.5)), Stage.CLOSE)

        close = stage == Stage.CLOSE
        self.closure[close] = np.clip((self.timer - PAUSE_SECONDS) / CLOSE_SECONDS, 0, 1)[close]
        closed = close & (self.timer > PAUSE_SECONDS + CLOSE_SECONDS + SETTLE_SECONDS)
        top = items[rows, self.top]
        self.held[closed] = np.einsum("nji,nj->ni", palm_rot, top - palm)[closed]
        for i in np.flatnonzero(closed):
            self.turn[i] = self._place_turn(i, yaws)
        self._advance(closed, Stage.CARRY)

        carry = stage == Stage.CARRY
        if carry.any():
            base = items[rows, self.base]
            top_h, base_h = self.rest[self.top], self.rest[self.base]
            # The held item's lowest point, not its centre, goes onto the base: a
            # pinched item hangs tilted, and lowering its centre to the resting height
            # would drive its low end into the base's edge and tip the base over.
            drop = top[:, 2] - self._lowest(rows, self.top)
            place = base + np.column_stack([np.zeros((n, 2)), base_h + drop - PLACE_PRESS])
            high = base[:, 2] + base_h + 2 * np.maximum(top_h, drop) + CARRY_CLEARANCE
            far = np.linalg.norm((place - top)[:, :2], axis=1) > 0.01
            goal = place.copy()
            goal[far, 2] = np.maximum(high, place[:, 2])[far]
            rising = far & (top[:, 2] < high - 0.02)
            goal[rising, :2] = top[rising, :2]
            error = goal - top
            target_pos[carry] = (self.pos + error)[carry]
            target_rot[carry] = (yawed(np.eye(3), self.turn) @ self.grasp_rot)[carry]
            expected = palm + np.einsum("nij,nj->ni", palm_rot, self.held)
            lost = carry & (np.linalg.norm(top - expected, axis=1) > LOST_DISTANCE)
            miss = np.linalg.norm(place - top, axis=1)
            placed = carry & ~lost & ((miss < PLACE_TOLERANCE)
                                      | ((miss < PLACE_NEAR) & (self.timer > PLACE_TIMEOUT)))
            self._advance(lost, Stage.DROP)
            self.let_go_from[placed] = self.pos[placed]
            self._advance(placed, Stage.RELEASE)

        release = stage == Stage.RELEASE
        self.closure[release] = np.maximum(0.0, 1.0 - self.timer / LET_GO_SECONDS)[release]
        # Sliding back while the fingers uncurl: their pads would roll the item off
        # towards the fingertips.
        slide = np.clip(self.timer / (LET_GO_SECONDS / 2) - 1.0, 0.0, 1.0) * RELEASE_SLIDE
        target_pos[release] = (self.let_go_from - slide[:, None] * self.rot[:, :, 0])[release]
        backing = release & (self.timer > LET_GO_SECONDS)
        target_pos[backing] = (self.pos - BACK_OFF * self.rot[:, :, 2])[backing]
        released = release & (self.timer > LET_GO_SECONDS + OPEN_SECONDS)
        base = items[rows, self.base]
        on_base = ((np.linalg.norm((top - base)[:, :2], axis=1) < STACKED_XY)
                   & (top[:, 2] > base[:, 2] + self.rest[self.base]))
        self._advance(released & ~on_base, Stage.REACH)
        self.travel_z[released & on_base] = (np.maximum(
            self.pos[:, 2], top[:, 2] + self.rest[self.top]) + TRAVEL_RISE)[released & on_base]
        self._advance(released & on_base, Stage.RISE)

        side_rot = _side_frame(self._side_yaw(yaws))
        side_pos = _side_grasp(items[rows, self.base], side_rot, self.offset)
        side_above = side_pos - APPROACH_HEIGHT * side_rot[:, :, 2]
        rise = stage == Stage.RISE
        target_pos[rise] = np.column_stack([self.pos[:, :2], self.travel_z])[rise]
        self._advance(rise & (self.pos[:, 2] > self.travel_z - 0.005), Stage.TURN)

        turn = stage == Stage.TURN
        over = np.column_stack([side_above[:, :2], self.travel_z])
        target_pos[turn], target_rot[turn] = over[turn], side_rot[turn]
        self._advance(turn & (np.linalg.norm(self.pos - over, axis=1) < 0.01)
                      & (self.timer > 0.5), Stage.LOWER)

        lower = stage == Stage.LOWER
        target_pos[lower], target_rot[lower] = side_above[lower], side_rot[lower]
        self._advance(lower & (np.linalg.norm(self.pos - side_above, axis=1) < 0.005),
                      Stage.ENTER)

        enter = stage == Stage.ENTER
        target_pos[enter], target_rot[enter] = side_pos[enter], side_rot[enter]
        at_side = ((np.linalg.norm(self.pos - side_pos, axis=1) < 0.005)
                   & (np.linalg.norm(palm - side_pos, axis=1) < ARRIVED))
        self._advance(enter & (at_side | (self.timer > 2.5)), Stage.GRIP)

        grip = stage == Stage.GRIP
        self.closure[grip] = np.clip((self.timer - PAUSE_SECONDS) / CLOSE_SECONDS, 0, 1)[grip]
        gripped = grip & (self.timer > PAUSE_SECONDS + CLOSE_SECONDS + SETTLE_SECONDS)
        self.lift_from[gripped] = self.pos[gripped]
        self._advance(gripped, Stage.LIFT)

        lift = stage == Stage.LIFT
        target_pos[lift] = (self.lift_from + [0.0, 0.0, LIFT_HEIGHT])[lift]
        heights = items[:, :, 2] - TABLE_TOP_Z - self.rest
        up = np.minimum(heights[rows, self.top], heights[rows, self.base])
        fell = lift & (self.pos[:, 2] - self.lift_from[:, 2] > LIFT_CHECK) & (up < LIFTED)
        self._advance(fell, Stage.DROP)

        drop = stage == Stage.DROP
        self.closure[drop] = np.minimum(self.closure, np.maximum(
            0.0, 1.0 - self.timer / OPEN_SECONDS))[drop]
        target_pos[drop] = np.where((self.timer > OPEN_SECONDS)[:, None],
                                    self.pos - BACK_OFF * self.rot[:, :, 2], self.pos)[drop]
        self._advance(drop & (self.timer > 2 * OPEN_SECONDS), Stage.REACH)

        speed = np.full(n, SPEED)
        speed[(stage == Stage.DESCEND) | (stage == Stage.CARRY) | (stage == Stage.ENTER)] = (
            CAREFUL_SPEED)
        speed[stage == Stage.LIFT] = LIFT_SPEED
        self.pos, self.rot = step_towards(self.pos, self.rot, target_pos, target_rot,
                                          speed[:, None] * self._dt, TURN_RATE * self._dt)
        actions = self.adapter.actions({self.side: HandCommand(self.pos, self.rot,
                                                               np.zeros(n))})
        sided = (stage >= Stage.RISE) & (stage <= Stage.LIFT)
        start = np.where(sided[:, None], self._ready, self._open)
        closed = np.stack([self._closed[self.names[t]] for t in self.top])
        closed[stage > Stage.RELEASE] = self._power
        closure = np.repeat(self.closure[:, None], len(self._hand), axis=1)
        # Letting go on the base: the thumb opens first from a power grasp, last from a
        # pinch (the pinched item would roll off over the thumb's side otherwise).
        release = stage == Stage.RELEASE
        half = LET_GO_SECONDS / 2
        first = np.clip(1.0 - self.timer / half, 0.0, 1.0)
        second = np.clip(2.0 - self.timer / half, 0.0, 1.0)
        thumb_first = np.array([self.items[self.names[t]].synergy == "power" for t in self.top])
        thumb_c, finger_c = np.where(thumb_first, first, second), np.where(thumb_first,
                                                                           second, first)
        closure[release] = np.where(self._thumb, thumb_c[:, None],
                                    finger_c[:, None])[release]
        fingers = start + closure * (closed - start)
        actions[:, self._hand] = torch.as_tensor(fingers, dtype=actions.dtype,
                                                 device=actions.device)
        return actions

    def _lowest(self, rows: np.ndarray, shape: np.ndarray) -> np.ndarray:
        """(N,) world z of the lowest point of shapes (N,) (indices) in envs `rows`."""
        model, view = self.env.scene.model, self.env.view
        low = np.full(len(rows), np.inf)
        for k, name in enumerate(self.names):
            mine = shape == k
            if not mine.any():
                continue
            quat = view.body_quat(name).cpu().numpy()[rows[mine]]
            body_rot = np.zeros((len(quat), 9))
            for j, q in enumerate(quat):
                mujoco.mju_quat2Mat(body_rot[j], q)
            body_rot = body_rot.reshape(-1, 3, 3)
            centre = view.body_pos(name).cpu().numpy()[rows[mine], 2]
            for g in self._geoms[k]:
                local = np.zeros(9)
                mujoco.mju_quat2Mat(local, model.geom_quat[g])
                rot = body_rot @ local.reshape(3, 3)
                z = centre + body_rot[:, 2] @ model.geom_pos[g]
                low[mine] = np.minimum(low[mine], z - _reach(model.geom_type[g],
                                                             model.geom_size[g], rot[:, 2]))
        return low

    def _place_turn(self, i: int, yaws: np.ndarray) -> float:
        """Yaw (rad) the hand turns while carrying so the top item lines up on the base."""
        item = self.items[self.names[self.top[i]]]
        if item.period is None:
            return 0.0
        desired = self._side_yaw(yaws)[i] + (np.pi / 2 if item.across else 0.0)
        k = 2 * np.pi / item.period
        return float(wrap(k * (desired - yaws[i, self.top[i]])) / k)

    def _advance(self, mask: np.ndarray, stage: Stage) -> None:
        self.stage[mask] = stage
        self.timer[mask] = 0.0


def _reach(kind: int, size: np.ndarray, up: np.ndarray) -> np.ndarray:
    """(N,) how far a geom (MuJoCo type and size) reaches below its centre along world z,
    given world z in its frame (N, 3)."""
    axial = np.abs(up[:, 2])
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return np.abs(up) @ size
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return size[0] + size[1] * axial
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return size[0] * np.sqrt(np.clip(1.0 - axial**2, 0.0, 1.0)) + size[1] * axial
    return np.full(len(up), size[0])


def _side_frame(heading: np.ndarray) -> np.ndarray:
    """(N, 3, 3) hand frames of the side grasp: fingers along `heading` (N,), rolled
    from palm-down so that the thumb side is underneath."""
    c, s = np.cos(-SIDE_ROLL), np.sin(-SIDE_ROLL)
    return palm_down(heading) @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _side_grasp(centre: np.ndarray, rot: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """(N, 3) palm positions of side grasps (frames `rot`) of items centred at `centre`."""
    pos = centre - rot @ (offset + np.asarray(SIDE_SHIFT))
    pos[:, 2] += SIDE_RISE
    return pos
