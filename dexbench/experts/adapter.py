"""Hand commands -> joint targets, for any embodiment.

Experts think in palm poses and grasp closure; this module turns those into the
embodiment's absolute joint targets. The mount (floating wrist or arm) goes through the
same damped least-squares IK on its joints either way, so one expert serves every mount;
the fingers blend between the hand's `open` pose and a synergy (`power`, `pinch`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import torch

from dexbench.embodiments.builder import set_joints
from dexbench.embodiments.ik import (
    POS_TOL,
    ROT_TOL,
    Clearance,
    multi_turn,
    path_blocked,
    pose_residual,
    solve_site_pose,
)
from dexbench.envs.dex_env import DexEnv

IK_ITERATIONS = 10
TABLE_CLEARANCE = 0.01  # m: arm links kept above the table top
# A multi-turn joint this far behind its target (rad) and this slow towards it (rad/s)
# has stalled: only then is its path checked (the check costs; a joint turning fast
# trails by 0.2-0.8 rad).
TURN_LAG, STALL_SPEED = 0.5, 0.1
RECHECK_SECONDS = 0.5  # a stall where neither way is clear is checked again this late
REACH_ITERATIONS = 100  # `reach_cost`: IK iterations per pose, as the feasibility test's
# Poses missed by at most this much more (`reach_cost`) than the least missed count as
# good as those: the scratch IK that scores them is a guess of the adapter's, which follows
# the way there step by step (the pour's vessel turn, the pusher's yaw, tilt and lean).
REACH_MARGIN = 1.0


def subtree(model: mujoco.MjModel, root: int) -> set[int]:
    """The ids of body `root` and of every body below it."""
    out = {root}
    for body in range(root + 1, model.nbody):
        if model.body_parentid[body] in out:
            out.add(body)
    return out


def collidable(model: mujoco.MjModel, body: int) -> list[int]:
    """A body's geoms that take part in collisions."""
    first = model.body_geomadr[body]
    return [g for g in range(first, first + model.body_geomnum[body])
            if model.geom_contype[g] or model.geom_conaffinity[g]]


def nearly_best(costs: Sequence[float]) -> int:
    """Index of the first of `costs` (options' `ActionAdapter.reach_cost`, in the order
    they are preferred) within `REACH_MARGIN` of the least."""
    return next(k for k, c in enumerate(costs) if c <= min(costs) + REACH_MARGIN)


@dataclass
class HandCommand:
    """What one hand should do in every env: palm site pose and finger closure.

    `pos` (N, 3) world; `rot` (N, 3, 3) the hand frame's axes as columns (x along the
    fingers, z the palm normal's opposite side: see `HandSpec.grasp_offset`);
    `closure` (N,) in [0, 1] from `open` to `synergy`.
    """

    pos: np.ndarray
    rot: np.ndarray
    closure: np.ndarray
    synergy: str = "power"


def site_pose(env: DexEnv, site: int) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) positions and (N, 3, 3) frames of one site in every env (copies: the
    simulator overwrites its arrays on the next step)."""
    sim = env.sim
    pos = sim.field("site_xpos")[:, site].cpu().numpy().copy()
    return pos, sim.field("site_xmat")[:, site].cpu().numpy().reshape(-1, 3, 3).copy()


def tips_in_palm_frame(env: DexEnv, palm: int, tips: list[int],
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The palm site's pose in every env and the fingertip sites' offsets from it in the
    palm frame, (N, len(tips), 3): where the fingers are, whatever the palm's pose."""
    pos, rot = site_pose(env, palm)
    sites = env.sim.field("site_xpos").cpu().numpy()[:, tips]
    return pos, rot, np.einsum("nji,nkj->nki", rot, sites - pos[:, None])


def palm_and_finger_sites(env: DexEnv, side: str) -> tuple[int, list[int]]:
    """Site ids of a hand's palm and of its fingertips without the thumb (listed first)."""
    model = env.scene.model
    layout = env.embodiment.sides[side]
    return (model.site(layout.palm_site).id,
            [model.site(s).id for s in layout.fingertip_sites[1:]])


class ActionAdapter:
    """Solves mount IK per env (warm-started from the last solution) and blends fingers.

    With `commanded_hand` the IK places the palm as if the hand's own joints (a wrist
    between the mount and the palm: the Shadow hand's) stood at their commanded targets,
    not where they are measured: a heavy held object swings a weak wrist, and a mount
    that takes out each swing drives it further (the object is flung out of the grip).

    On an arm the IK keeps the arm's links `TABLE_CLEARANCE` above the table top, trading
    the palm's pose for it: the plans pose a palm low over the table, as the floating
    hand allows, where a flange beside the hand (the FR3's, carrying it flat) would land
    on the table and prop the palm off its pose. The hand's own parts (the Shadow
    forearm) meet the table as they do on the floating mount.

    A joint that turns more than a full turn (the UR10e's, the xArm7's) reaches the same
    pose at `q - 2 pi` or `q + 2 pi`; the warm-started IK keeps following the one it
    started near, whichever way is blocked. Turning the palm ~110 deg about the vertical
    (GraspPan) drove the UR10e's wrist 2 from 1.17 to 3.80 rad, the Shadow forearm into
    wrist 1 at 2.78 rad, and there it stalled with the palm 0.33 m off its target; the
    same pose at -2.48 rad is a clear turn the other way. So when such a joint stalls
    short of its target (`TURN_LAG`, `STALL_SPEED`) and the straight joint path from the
    measured joints to the target drives the arm into itself, its hand or anything it
    would touch (`_path_pairs`), the target goes the other way round if that path is
    clear (`_other_way_round`). The IK goes on from the answer. An arm held where
    neither way is clear is checked again only after `RECHECK_SECONDS` (at every step,
    the checks cost a quarter of GraspCup's time on the UR10e).
    """

    def __init__(self, env: DexEnv, commanded_hand: bool = False) -> None:
        self.env = env
        self.commanded_hand = commanded_hand
        model = env.scene.model
        self.model = model
        emb = env.embodiment
        self._scratch = mujoco.MjData(model)
        self._sides = {}
        self._hand_joints: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        joint_of = {model.actuator(a).name: model.joint(model.actuator_trnid[a, 0]).name
                    for a in range(model.nu)
                    if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT}
        for side, layout in emb.sides.items():
            mount = [i for i in emb.side_actuators(side)
                     if joint_of.get(emb.actuators[i]) in layout.mount_joints]
            joints = [joint_of[emb.actuators[i]] for i in mount]
            self._sides[side] = (layout.palm_site, joints, np.array(mount),
                                 emb.hand_actuators(side))
            # The hand's joint-driven actuators: (action index, qpos address, gear).
            held = [i for i in emb.hand_actuators(side) if emb.actuators[i] in joint_of]
            self._hand_joints[side] = (
                np.array(held, dtype=int),
                np.array([model.joint(joint_of[emb.actuators[i]]).qposadr[0] for i in held],
                         dtype=int),
                np.array([model.actuator(emb.actuators[i]).gear[0] for i in held]))
        self._clearance = ({} if emb.mount == "floating" else
                           {side: self._table_clearance(side) for side in emb.sides})
        self._turns = {side: multi_turn(model, joints)
                       for side, (_, joints, _, _) in self._sides.items()}
        self._pairs = {side: self._path_pairs(side) for side in emb.sides
                       if self._turns[side].any()}
        self._poses = emb.poses
        self._solution: dict[str, np.ndarray] = {}
        self._recheck = round(RECHECK_SECONDS / env.control_dt)
        self._hold: dict[str, np.ndarray] = {}  # per side: each env's steps to the next check

    def _table_clearance(self, side: str) -> Clearance | None:
        """An arm side's moving link geoms (above the hand's root) against the table top
        and against the hand's mount part (`_mount_part`); None without a table."""
        model = self.model
        try:
            table = model.geom("table_top").id
        except KeyError:
            return None
        moving, _ = self._arm_links(side)
        return Clearance(tuple((g, table) for g in moving) + self._mount_part(side, moving),
                         TABLE_CLEARANCE)

    def _mount_part(self, side: str, links: list[int]) -> tuple[tuple[int, int], ...]:
        """(link, hand geom) pairs of the hand's part rigid with its root (the Shadow
        forearm) that the simulator lets touch and that stand clear at home: turning the
        palm through the wrist can drive that part into the arm's own forearm link, where
        the contact stalls the wrist joint short of its target (the FR3's link 5 held a
        Shadow hand's pour turn to 20 of 100 degrees)."""
        model, data = self.model, self._scratch
        root = model.body(self.env.embodiment.sides[side].hand_root).id
        part = [g for b in subtree(model, root) if model.body_weldid[b] == model.body_weldid[root]
                for g in collidable(self.model, b)]
        data.qpos[:] = model.qpos0
        set_joints(model, data, self.env.embodiment.sides[side].home_qpos)
        mujoco.mj_kinematics(model, data)
        fromto = np.zeros(6)
        return tuple((a, b) for a in links for b in part if self._collide(a, b)
                     and mujoco.mj_geomDistance(model, data, a, b, 1.0, fromto)
                     > TABLE_CLEARANCE)

    def _arm_links(self, side: str) -> tuple[list[int], int]:
        """A side's moving arm link geoms (those that collide, from the hand's root up to
        the fixed base) and the topmost moving body."""
        model = self.model
        top = model.body(self.env.embodiment.sides[side].hand_root).id
        body, links = model.body_parentid[top], []
        while model.body_weldid[body]:
            links += collidable(self.model, body)
            top, body = body, model.body_parentid[body]
        return links, top

    def _path_pairs(self, side: str) -> tuple[tuple[int, int], ...]:
        """The geom pairs a path of this side's mount must not drive into each other,
        where the simulator would make contacts between them: its moving links against
        each other, and links and hand against its own hand and everything else (the
        table, the objects, another arm). The hand's own pairs move as one."""
        model = self.model
        links, top = self._arm_links(side)
        hand_bodies = subtree(model, model.body(self.env.embodiment.sides[side].hand_root).id)
        hand = [g for b in sorted(hand_bodies) for g in collidable(self.model, b)]
        moving, mount = set(links + hand), subtree(model, top)
        rest = [g for b in range(model.nbody) if b not in mount for g in collidable(self.model, b)
                if g not in moving]
        pairs = [(a, b) for i, a in enumerate(links) for b in links[i + 1:] + hand]
        pairs += [(a, b) for a in links + hand for b in rest]
        return tuple((a, b) for a, b in pairs if self._collide(a, b))

    def _collide(self, geom: int, other: int) -> bool:
        """Whether the simulator makes contacts between two geoms: their bit masks
        match and MuJoCo's filters (one weld, a parent welded to its child, an
        `exclude`) let the pair through."""
        model = self.model
        if not (model.geom_contype[geom] & model.geom_conaffinity[other]
                or model.geom_contype[other] & model.geom_conaffinity[geom]):
            return False
        body = model.geom_bodyid[[geom, other]]
        weld = model.body_weldid[body]
        parents = model.body_weldid[model.body_parentid[weld]]
        if weld[0] == weld[1] or parents[0] == weld[1] or parents[1] == weld[0]:
            return False
        excluded = set(model.exclude_signature.tolist())
        return not {(int(body[0]) << 16) + int(body[1]),
                    (int(body[1]) << 16) + int(body[0])} & excluded

    def _other_way_round(self, side: str, env: int, qadr: np.ndarray, qpos: np.ndarray,
                         speed: np.ndarray, target: np.ndarray) -> np.ndarray:
        """`target` (the mount joints), or its equivalent with a stalled multi-turn joint
        a full turn the other way, whichever is nearest the measured joints (`qpos`, the
        env's whole qpos; `speed`, the mount joints' velocities) along a straight joint
        path that drives no pair of `_path_pairs` into each other; `target` when none is
        clear."""
        ahead = target - qpos[qadr]
        trailing = np.flatnonzero(self._turns[side] & (np.abs(ahead) > TURN_LAG)
                                  & (speed * np.sign(ahead) < STALL_SPEED))
        hold = self._hold[side]
        hold[env] -= 1
        if not len(trailing) or hold[env] > 0:
            return target
        chosen = self._clear_turn(side, qadr, qpos, target, ahead, trailing)
        hold[env] = self._recheck if chosen is target else 0
        return chosen

    def _clear_turn(self, side: str, qadr: np.ndarray, qpos: np.ndarray, target: np.ndarray,
                    ahead: np.ndarray, trailing: np.ndarray) -> np.ndarray:
        """The nearest of `target` and its turns of one `trailing` joint the other way
        whose path from the measured joints is clear; `target` when none is (one joint at
        a time: the paths are checked one by one, and each costs)."""
        data, model, pairs = self._scratch, self.model, self._pairs[side]
        joint = [model.joint(j) for j in self._sides[side][1]]
        options = [target]
        for j in trailing:
            turned = target.copy()
            turned[j] -= 2 * np.pi * np.sign(ahead[j])
            lo, hi = joint[j].range if joint[j].limited[0] else (-np.inf, np.inf)
            if lo <= turned[j] <= hi:
                options.append(turned)
        if len(options) == 1:
            return target
        options.sort(key=lambda q: np.abs(q - qpos[qadr]).max())
        for q in options:
            data.qpos[:] = qpos
            if not path_blocked(model, data, qadr, qpos[qadr], q, pairs):
                return q
        return target

    def reach_cost(self, side: str, env: int, poses: list[tuple[np.ndarray, np.ndarray]],
                   iterations: int = REACH_ITERATIONS) -> float:
        """How badly this side's mount misses a sequence of palm poses (position,
        frame), each solved from the last one's solution, the first from env `env`'s
        measured joints, as the adapter's IK would follow them: the largest of the poses'
        position residual / `ik.POS_TOL` + orientation residual / `ik.ROT_TOL` (below 1:
        every pose taken; ~0 on a floating mount). Kinematic only: a path through the
        arm's own links is not seen."""
        data, model = self._scratch, self.model
        site, joints, _, _ = self._sides[side]
        sid = model.site(site).id
        data.qpos[:] = self.env.sim.field("qpos")[env].cpu().numpy()
        worst = 0.0
        for pos, rot in poses:
            solve_site_pose(model, data, site, joints, pos, rot, iterations=iterations,
                            clearance=self._clearance.get(side))
            miss, turn = pose_residual(model, data, sid, pos, rot)
            worst = max(worst, miss / POS_TOL + turn / ROT_TOL)
        return float(worst)

    def pose(self, name: str) -> np.ndarray:
        """A named pose (every actuator's target) commands can blend towards."""
        return self._poses[name]

    def add_pose(self, name: str, targets: np.ndarray) -> None:
        """One more pose for this adapter's commands (an expert's own closure); the
        embodiment's pose table stays as it is."""
        self._poses = {**self._poses, name: np.asarray(targets)}

    def reset(self, env_ids: np.ndarray) -> None:
        """Forget warm starts of these envs (their robots are back at home)."""
        for side, (_, joints, _, _) in self._sides.items():
            if side in self._hold:
                self._hold[side][env_ids] = 0
            if side in self._solution:
                qadr = [self.model.joint(j).qposadr[0] for j in joints]
                qpos = self.env.sim.field("qpos").cpu().numpy()
                self._solution[side][env_ids] = qpos[np.ix_(env_ids, qadr)]

    def actions(self, commands: dict[str, HandCommand]) -> torch.Tensor:
        """(N, action_dim) joint targets realising `commands` (one per hand side)."""
        n = self.env.num_envs
        qpos = self.env.sim.field("qpos").cpu().numpy()
        qvel = self.env.sim.field("qvel").cpu().numpy() if self._pairs else None
        out = np.repeat(self._poses["home"][None], n, axis=0)
        data, model = self._scratch, self.model
        for side, cmd in commands.items():
            site, joints, mount, hand = self._sides[side]
            qadr = np.array([model.joint(j).qposadr[0] for j in joints])
            dadr = np.array([model.joint(j).dofadr[0] for j in joints])
            if side not in self._solution:
                self._solution[side] = qpos[:, qadr].copy()
                self._hold[side] = np.zeros(n, dtype=int)
            opened, closed = self._poses["open"][hand], self._poses[cmd.synergy][hand]
            c = np.clip(cmd.closure, 0.0, 1.0)[:, None]
            out[:, hand] = opened + c * (closed - opened)
            held, held_adr, gear = self._hand_joints[side]
            clearance = self._clearance.get(side)
            for i in range(n):
                data.qpos[:] = qpos[i]
                data.qpos[qadr] = self._solution[side][i]
                if self.commanded_hand:
                    data.qpos[held_adr] = out[i, held] / gear
                q, _ = solve_site_pose(model, data, site, joints, cmd.pos[i], cmd.rot[i],
                                       iterations=IK_ITERATIONS, clearance=clearance)
                if side in self._pairs:
                    q = self._other_way_round(side, i, qadr, qpos[i], qvel[i, dadr], q)
                self._solution[side][i] = q
            out[:, mount] = self._solution[side]
        return torch.as_tensor(out, device=self.env.device)
