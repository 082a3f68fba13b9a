"""Facts about a hand derived from its model, so no hand needs hand-tuned mount poses.

The *hand frame* H has its origin at the palm body (for a left model whose palm body
lies elsewhere on the hand than its right model's: at the mirror image of the right's),
x along the fingers (from the mean non-thumb knuckle to the mean non-thumb fingertip,
hand open: knuckles rather than the palm origin, which some models place far off the
fingers' line) and z along the palm normal (the way the fingers curl when the hand
closes). Every mount places H, not the
model's root, so "palm down, fingers forward" means the same thing for all six hands.
Everything here is in the hand file's world frame, which is what `MjSpec.attach` places.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from dexbench.assets.robots import robot_spec
from dexbench.embodiments.hands import HANDS, SIDES, SOFT_CONTACT, SYNERGIES, HandSpec

_MAX_SETTLE_STEPS = 2000  # 4 s at the 2 ms timestep used here
# m: a left model whose knuckles lie further than this from the mirror image of the right
# model's (in H) has its palm origin elsewhere on the hand; H's origin is moved to the
# mirror of the right's (LEAP's left palm origin sits 8 cm off its right's). Closer
# than this, the models' own asymmetry (Sharpa, Wuji: < 0.5 mm) is left alone.
_MIRROR_TOLERANCE = 0.005


@dataclass(frozen=True)
class HandGeometry:
    """Hand-frame pose, fingertip points and synergy targets of one hand side.

    Besides each hand's declared synergies, every hand gets `hook`: `power` on the
    fingers, `open` on the thumb (derived, unless the hand declares its own)."""

    frame_pos: np.ndarray  # (3,) origin of H in the hand file's world frame
    frame_rot: np.ndarray  # (3, 3) columns: H's x (fingers), y, z (palm normal)
    fingertip_offsets: tuple[np.ndarray, ...]  # per fingertip body, in its body frame
    palm_site_pos: np.ndarray  # H's origin in the palm body frame
    knuckles: np.ndarray  # (3,) the mean non-thumb knuckle of the open hand, in H
    palm_site_quat: np.ndarray  # H's orientation in the palm body frame
    corners: np.ndarray  # (n, 3) corners of the open hand's geom bounding boxes, in H
    actuators: tuple[str, ...]  # unprefixed actuator names, model order
    synergies: dict[str, np.ndarray]  # name -> (nu_hand,) targets
    open_qpos: dict[str, float]  # settled joint positions of the open hand, by joint

    def extent_behind(self, axis: np.ndarray) -> float:
        """How far (m) the open hand reaches behind H's origin against `axis` (unit, in H):
        a mount plate through the origin, normal to `axis`, must stand off this much."""
        return float(max(0.0, -np.min(self.corners @ axis)))


def hand_model_spec(hand: HandSpec, side: str) -> mujoco.MjSpec:
    """The hand's spec with its keyframes removed (they would not fit a composed scene)
    and, for a hand with `soft_contacts`, the Shadow hand's contact softness."""
    spec = robot_spec(hand.collection, hand.sides[side].entry)
    for key in list(spec.keys):
        spec.delete(key)
    if hand.soft_contacts:
        solref, solimp = SOFT_CONTACT
        for geom in spec.geoms:
            geom.solref, geom.solimp = solref, solimp
    return spec


def synergy_targets(
    patterns: dict[str, float], names: tuple[str, ...], ranges: np.ndarray, base: np.ndarray
) -> np.ndarray:
    """Resolve a synergy's name patterns into per-actuator targets, clipped to range."""
    out = base.copy()
    for i, name in enumerate(names):
        for pattern, value in patterns.items():
            if re.search(pattern, name):
                out[i] = value
                break
    return np.clip(out, ranges[:, 0], ranges[:, 1])


def _standalone(spec: mujoco.MjSpec) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Compile a hand model for the gravity-free 2 ms simulation its measurements use."""
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.timestep = 0.002
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    model = spec.compile()
    return model, mujoco.MjData(model)


def _settle(model: mujoco.MjModel, data: mujoco.MjData, ctrl: np.ndarray) -> None:
    """Drive the hand to `ctrl` from rest until it stops moving (at most 4 s)."""
    mujoco.mj_resetData(model, data)
    data.ctrl[:] = ctrl
    for step in range(_MAX_SETTLE_STEPS):
        mujoco.mj_step(model, data)
        if step > 100 and np.abs(data.qvel).max() < 1e-4:
            break


@functools.cache
def hand_geometry(hand_name: str, side: str) -> HandGeometry:
    """Measure one hand side by closing it in a gravity-free standalone simulation."""
    hand = HANDS[hand_name]
    parts = hand.sides[side]
    model, data = _standalone(hand_model_spec(hand, side))
    names = tuple(model.actuator(i).name for i in range(model.nu))
    ranges = model.actuator_ctrlrange.copy()
    zero = np.zeros(model.nu)
    open_ = synergy_targets(hand.synergies.get("open", {}), names, ranges, zero)
    synergies = {
        s: synergy_targets(hand.synergies.get(s, {}), names, ranges, open_)
        for s in SYNERGIES if s != "hook" or s in hand.synergies
    }

    palm = model.body(parts.palm_body).id
    tips = [model.body(b).id for b in parts.fingertip_bodies]
    thumb = thumb_actuators(model, palm, tips[0])
    if "hook" not in hand.synergies:
        synergies["hook"] = np.where(thumb, synergies["open"], synergies["power"])
    _settle(model, data, synergies["open"])
    open_qpos = {
        model.joint(j).name: float(data.qpos[model.jnt_qposadr[j]]) for j in range(model.njnt)
    }
    palm_pos = data.xpos[palm].copy()
    open_tips = data.xipos[tips[1:]].mean(axis=0)
    knuckles = data.xpos[[_knuckle(model, t, palm) for t in tips[1:]]].mean(axis=0)
    geom_corners = _geom_corners(model, data)
    _settle(model, data, synergies["power"])
    closed_tips = data.xipos[tips[1:]].mean(axis=0)

    x = open_tips - knuckles
    x /= np.linalg.norm(x)
    curl = closed_tips - open_tips
    z = curl - curl.dot(x) * x
    z /= np.linalg.norm(z)
    rot = np.column_stack([x, np.cross(z, x), z])
    origin = palm_pos
    if side != SIDES[0] and SIDES[0] in hand.sides:
        # H is right-handed on both sides, the left hand a mirror image: across y.
        mirrored = hand_geometry(hand_name, SIDES[0]).knuckles * [1.0, -1.0, 1.0]
        off = rot.T @ (knuckles - palm_pos) - mirrored
        if np.linalg.norm(off) > _MIRROR_TOLERANCE:
            origin = palm_pos + rot @ off

    mujoco.mj_resetData(model, data)
    mujoco.mj_kinematics(model, data)
    palm_rot = data.xmat[palm].reshape(3, 3)
    site_quat = np.zeros(4)
    mujoco.mju_mat2Quat(site_quat, (palm_rot.T @ rot).ravel())
    return HandGeometry(
        frame_pos=origin,
        frame_rot=rot,
        fingertip_offsets=tuple(model.body_ipos[t].copy() for t in tips),
        palm_site_pos=palm_rot.T @ (origin - data.xpos[palm]),
        knuckles=rot.T @ (knuckles - origin),
        palm_site_quat=site_quat,
        corners=(geom_corners - origin) @ rot,
        actuators=names,
        synergies=synergies,
        open_qpos=open_qpos,
    )


def thumb_actuators(model: mujoco.MjModel, palm: int, thumb_tip: int) -> np.ndarray:
    """(nu,) bool: the actuators driving a joint on the chain from `palm` to `thumb_tip`
    (directly or through a tendon): `hook` keeps these open, so the thumb stays clear of
    what the curled fingers hold (a mug's rim)."""
    chain = set()
    body = thumb_tip
    while body not in (palm, 0):
        chain.add(body)
        body = model.body_parentid[body]
    out = np.zeros(model.nu, dtype=bool)
    for a in range(model.nu):
        out[a] = any(model.jnt_bodyid[j] in chain for j, _ in actuated_joints(model, a))
    return out


def actuated_joints(model: mujoco.MjModel, actuator: int) -> list[tuple[int, float]]:
    """(joint id, coefficient) of each joint an actuator drives: its joint (1.0), or the
    joints of its fixed tendon with their coefficients (coupled finger joints); none for
    other transmissions."""
    target = model.actuator_trnid[actuator, 0]
    if model.actuator_trntype[actuator] == mujoco.mjtTrn.mjTRN_JOINT:
        return [(int(target), 1.0)]
    if model.actuator_trntype[actuator] != mujoco.mjtTrn.mjTRN_TENDON:
        return []
    first = model.tendon_adr[target]
    return [(int(model.wrap_objid[w]), float(model.wrap_prm[w]))
            for w in range(first, first + model.tendon_num[target])
            if model.wrap_type[w] == mujoco.mjtWrap.mjWRAP_JOINT]


def _knuckle(model: mujoco.MjModel, body: int, palm: int) -> int:
    """The first body of a finger's chain: the ancestor of `body` attached to the palm."""
    while model.body_parentid[body] not in (palm, 0):
        body = model.body_parentid[body]
    return body


def _geom_corners(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """World-frame corners of every collision-or-visual geom's bounding box."""
    signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T
    corners = []
    for g in range(model.ngeom):
        center, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        local = center + signs * half
        corners.append(data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T)
    return np.concatenate(corners)


@functools.cache
def fingertip_thickness(hand_name: str, side: str) -> float:
    """Mean thickness (m) of the open hand's finger tips (thumb excluded) along the palm
    normal: what must fit into a gap for the tip to slide in flat (under an edge). Each is
    measured as the distance between two planes, normal to the palm, touching its collision
    geoms on either side."""
    hand = HANDS[hand_name]
    geo = hand_geometry(hand_name, side)
    spec = hand_model_spec(hand, side)
    normal = geo.frame_rot[:, 2]
    for sign in (1.0, -1.0):  # a plane 1 m out on each side, facing the hand
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, (geo.frame_rot @ np.diag([1.0, sign, sign])).ravel())
        spec.worldbody.add_geom(name=f"thickness_{sign:+.0f}", type=mujoco.mjtGeom.mjGEOM_PLANE,
                                size=[1.0, 1.0, 0.01], contype=0, conaffinity=0,
                                pos=(geo.frame_pos - sign * normal).tolist(), quat=quat.tolist())
    model, data = _standalone(spec)
    _settle(model, data, geo.synergies["open"])
    planes = [model.geom(f"thickness_{s:+.0f}").id for s in (1.0, -1.0)]
    fromto = np.zeros(6)
    out = []
    for body in hand.sides[side].fingertip_bodies[1:]:
        bid = model.body(body).id
        geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == bid
                 and (model.geom_contype[g] or model.geom_conaffinity[g])]
        gaps = [min(mujoco.mj_geomDistance(model, data, p, g, 2.0, fromto) for g in geoms)
                for p in planes]
        out.append(2.0 - sum(gaps))
    return float(np.mean(out))


_FACE_GRID = 0.004  # m between the rays that scan a palm's face
_FACE_SPAN = ((-0.15, 0.25), (-0.15, 0.15), (-0.1, 0.15))  # m: the scanned x, y, z, in H
_FACE_BAND = 0.01  # m: the face's parts this close to its outermost touch a pressed plane
_RAY_FROM = 0.5  # m out along the scan's direction from H's origin


@dataclass(frozen=True)
class PalmFace:
    """The open hand's pressing face: how far (m) its palm and non-thumb fingers stand out
    along the palm normal (H's z) at most, and the middle (H's x, y) of its parts within
    `_FACE_BAND` of that: where a flat surface pressed against the open hand bears. And
    `reach`: how far (m, H's x) its collision geoms reach along the fingers, thumb
    included (fingertip sites sit 1.5-3 cm short of the tips' surface)."""

    height: float
    centre: tuple[float, float]
    reach: float


def _scan(model: mujoco.MjModel, data: mujoco.MjData, geo: HandGeometry, axis: int,
          keep: Callable[[int], bool]) -> np.ndarray:
    """(n, 3) points, in H, where rays along H's -`axis` (from `_RAY_FROM` out, on a
    `_FACE_GRID` grid over the other two axes' `_FACE_SPAN`) first hit a collision geom
    (groups 0-4) of a body `keep` accepts."""
    groups = np.array([1, 1, 1, 1, 1, 0], dtype=np.uint8)
    hit = np.zeros(1, dtype=np.int32)
    across = [a for a in range(3) if a != axis]
    grids = [np.arange(*_FACE_SPAN[a], _FACE_GRID) for a in across]
    points = []
    for u in grids[0]:
        for v in grids[1]:
            local = np.zeros(3)
            local[across], local[axis] = (u, v), _RAY_FROM
            dist = mujoco.mj_ray(model, data, geo.frame_pos + geo.frame_rot @ local,
                                 -geo.frame_rot[:, axis], groups, 1, -1, hit)
            if dist >= 0 and keep(int(model.geom_bodyid[hit[0]])):
                local[axis] = _RAY_FROM - dist
                points.append(local)
    return np.array(points)


@functools.cache
def palm_face(hand_name: str, side: str) -> PalmFace:
    """Scan the open hand with rays along -z of H, from a plane in front of the palm,
    against the collision geoms of the palm and its fingers but the thumb (which sticks
    out of some palms, Sharpa's and Inspire's, and yields when pressed); and along -x
    for its reach. Pressing a box by the palm's site instead left some hands' faces 4 cm
    short of where others' were, and LEAP's face lies 4.5 cm to the side of its fingers'
    middle (its palm slopes across the hand)."""
    hand = HANDS[hand_name]
    parts = hand.sides[side]
    geo = hand_geometry(hand_name, side)
    spec = hand_model_spec(hand, side)
    for geom in spec.geoms:  # rays see only groups 0-4: visual geoms go to group 5
        if geom.contype == 0 and geom.conaffinity == 0:
            geom.group = 5
    model, data = _standalone(spec)
    _settle(model, data, geo.synergies["open"])
    palm = model.body(parts.palm_body).id
    thumb = set()
    body = model.body(parts.fingertip_bodies[0]).id
    while body not in (palm, 0):
        thumb.add(body)
        body = model.body_parentid[body]

    def on_hand(body: int) -> bool:
        while body not in (palm, 0):
            body = model.body_parentid[body]
        return body == palm

    face = _scan(model, data, geo, 2, lambda b: b not in thumb and on_hand(b))
    height = float(face[:, 2].max())
    bearing = face[face[:, 2] > height - _FACE_BAND]
    reach = _scan(model, data, geo, 0, on_hand)
    return PalmFace(height, (float(bearing[:, 0].mean()), float(bearing[:, 1].mean())),
                    float(reach[:, 0].max()))
