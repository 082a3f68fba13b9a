"""Compose any of the 48 embodiments into a scene spec.

Names are `<mount>_<hand>` (the right hand) and `bimanual_<mount>_<hand>`. Every element
of a side is prefixed `<side>/`: `right/wrist/x`, `right/arm/<joint>`, `right/hand/<name>`.
The action layout is the model's actuator order, right side first; actions are absolute
joint-position targets. The floating wrist's slide targets are displacements (m) from the
wrist base, its hinges rotations (rad) about the world axes.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import mujoco
import numpy as np

from dexbench.assets.objects import new_spec
from dexbench.assets.robots import robot_spec
from dexbench.embodiments.arms import ARMS
from dexbench.embodiments.hand_geometry import hand_geometry, hand_model_spec
from dexbench.embodiments.hands import HANDS, SYNERGIES, HandSpec
from dexbench.embodiments.ik import solve_site_pose

MOUNTS = ("floating", "fr3", "ur10e", "xarm7")
TABLE_TOP_Z = 0.6
TABLE_HALF_SIZE = (0.6, 0.75)  # table top spans x in [-0.6, 0.6], y in [-0.75, 0.75]
HOME_PALM_X = -0.25
HOME_PALM_Z = 0.8
DEFAULT_HOME_PALM = (HOME_PALM_X, 0.0, HOME_PALM_Z)  # one side's home, default workspace
# Where a task's hands work (world x, y, height above the table top) unless it declares
# otherwise (`Task.workspace`): the table centre. Arms and their homes are placed from it.
DEFAULT_WORKSPACE = (0.0, 0.0, 0.0)
BIMANUAL_Y = {"right": -0.3, "left": 0.3}
# Home orientation of the hand frame: fingers along +x, palm normal down (-z).
HOME_PALM_ROT = np.diag([1.0, -1.0, -1.0])

WRIST_AXES = (("x", 2, (1, 0, 0)), ("y", 2, (0, 1, 0)), ("z", 2, (0, 0, 1)),
              ("rx", 3, (1, 0, 0)), ("ry", 3, (0, 1, 0)), ("rz", 3, (0, 0, 1)))
WRIST_RANGE = {"x": (-0.6, 0.8), "y": (-0.6, 0.6), "z": (-0.3, 0.5),
               "rx": (-np.pi, np.pi), "ry": (-np.pi, np.pi), "rz": (-np.pi, np.pi)}
WRIST_KP = {2: 2000.0, 3: 300.0}  # by joint type: slide N/m, hinge Nm/rad
WRIST_FORCE = {2: 300.0, 3: 50.0}
WRIST_CAMERA_FOVY = 60.0


# Physics options a child model would otherwise try to impose on the composed scene.
_OPTION_FIELDS = ("timestep", "integrator", "cone", "impratio", "iterations", "ls_iterations",
                  "tolerance", "ls_tolerance", "jacobian", "solver", "noslip_iterations",
                  "gravity", "disableflags", "enableflags")


def _adopt_options(child: mujoco.MjSpec, parent: mujoco.MjSpec) -> None:
    """Give a child the parent's options: the parent's choice wins, without warnings."""
    for name in _OPTION_FIELDS:
        setattr(child.option, name, getattr(parent.option, name))


class UnknownEmbodimentError(ValueError):
    """An embodiment name outside the registry."""


@dataclass(frozen=True)
class EmbodimentName:
    mount: str
    hand: str
    bimanual: bool

    @property
    def sides(self) -> tuple[str, ...]:
        return ("right", "left") if self.bimanual else ("right",)

    @property
    def arity(self) -> int:
        """How many hands: 1 or 2."""
        return len(self.sides)

    @property
    def hand_spec(self) -> HandSpec:
        return HANDS[self.hand]

    def __str__(self) -> str:
        return f"{'bimanual_' if self.bimanual else ''}{self.mount}_{self.hand}"


def embodiment_names() -> list[str]:
    """All 48 embodiment names: single first, then bimanual."""
    return [
        str(EmbodimentName(m, h, b)) for b in (False, True) for m in MOUNTS for h in HANDS
    ]


def parse_embodiment(name: str) -> EmbodimentName:
    """Split a name into mount, hand and arity, or say which names exist."""
    bimanual = name.startswith("bimanual_")
    rest = name.removeprefix("bimanual_")
    mount, _, hand = rest.partition("_")
    if mount not in MOUNTS or hand not in HANDS:
        raise UnknownEmbodimentError(
            f"unknown embodiment {name!r}: use <mount>_<hand> or bimanual_<mount>_<hand> "
            f"with mount in {MOUNTS} and hand in {tuple(HANDS)} "
            "(`python -m dexbench list embodiments` lists all)"
        )
    return EmbodimentName(mount, hand, bimanual)


def embodiment_arity(name: str) -> int:
    """How many hands embodiment `name` has (1 or 2)."""
    return parse_embodiment(name).arity


def other_hands(name: str) -> list[str]:
    """The embodiments with `name`'s mount and arity but another hand, in registry order."""
    ref = parse_embodiment(name)
    return [other for other in embodiment_names() if other != name
            and (parse_embodiment(other).mount, parse_embodiment(other).bimanual)
            == (ref.mount, ref.bimanual)]


@dataclass(frozen=True)
class SideLayout:
    """Named parts of one side of a composed embodiment (all names prefixed)."""

    side: str
    base_body: str  # fixed robot base: contact forces are expressed in its frame
    palm_site: str  # the hand frame H
    fingertip_bodies: tuple[str, ...]
    fingertip_sites: tuple[str, ...]
    mount_joints: tuple[str, ...]
    hand_joints: tuple[str, ...]
    home_palm_pos: tuple[float, float, float]
    home_qpos: dict[str, float] = field(default_factory=dict)
    hand_root: str = ""  # the hand model's root body: its subtree is the whole hand


@dataclass(frozen=True)
class EmbodimentPlan:
    """What `add_embodiment` put into a spec, before compilation fixes the indices."""

    name: EmbodimentName
    sides: dict[str, SideLayout]
    hand_targets: dict[str, dict[str, float]]  # synergy -> hand actuator -> target
    hand_qpos: dict[str, float]  # settled open-hand joint positions


def _quat(rot: np.ndarray) -> list[float]:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(rot).ravel())
    return q.tolist()


def _wrist_camera_pose(palm_site_quat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Wrist camera pose in the palm body frame, from its placement in the hand frame.

    It sits at the heel of the palm, on the palm side (hand frame (-0.05, 0, 0.05)), and
    looks along the fingers at the grasp region, with the back of the hand up.
    """
    h_rot = np.zeros(9)
    mujoco.mju_quat2Mat(h_rot, palm_site_quat)
    h_rot = h_rot.reshape(3, 3)
    eye, target = np.array([-0.05, 0.0, 0.05]), np.array([0.12, 0.0, 0.07])
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, -1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return h_rot @ eye, h_rot @ np.column_stack([right, up, -forward])


def _mark_robot(body: mujoco.MjsBody) -> None:
    """Gravity-compensate a robot subtree, as real arm and hand controllers do."""
    body.gravcomp = 1.0
    for child in body.bodies:
        _mark_robot(child)


def _attach_hand(
    spec: mujoco.MjSpec, parent: mujoco.MjsBody, hand: str, side: str,
    frame_rot: np.ndarray, frame_pos: np.ndarray,
) -> tuple[list[str], list[str], list[str], str]:
    """Attach a hand so its hand frame H lands at (frame_pos, frame_rot) in `parent`;
    returns its joints, fingertip bodies and sites, and its root body."""
    geo = hand_geometry(hand, side)
    parts = HANDS[hand].sides[side]
    child = hand_model_spec(HANDS[hand], side)
    _adopt_options(child, spec)
    for body_name, offset in zip(parts.fingertip_bodies, geo.fingertip_offsets, strict=True):
        child.body(body_name).add_site(name=f"tip_{body_name}", pos=offset.tolist(),
                                       size=[0.004, 0, 0], group=4)
    palm = child.body(parts.palm_body)
    palm.add_site(name="palm", pos=geo.palm_site_pos.tolist(), quat=geo.palm_site_quat.tolist(),
                  group=4)
    cam_pos, cam_rot = _wrist_camera_pose(geo.palm_site_quat)
    palm.add_camera(name="wrist_cam", pos=(geo.palm_site_pos + cam_pos).tolist(),
                    quat=_quat(cam_rot),
                    fovy=WRIST_CAMERA_FOVY)
    root_rot = frame_rot @ geo.frame_rot.T
    root_pos = frame_pos - root_rot @ geo.frame_pos
    frame = parent.add_frame(pos=root_pos.tolist(), quat=_quat(root_rot))
    prefix = f"{side}/hand/"
    hand_joints = [prefix + j.name for j in child.joints]
    root = prefix + child.worldbody.first_body().name
    spec.attach(child, prefix=prefix, frame=frame)
    tips = [prefix + b for b in parts.fingertip_bodies]
    tip_sites = [f"{prefix}tip_{b}" for b in parts.fingertip_bodies]
    return hand_joints, tips, tip_sites, root


def _add_floating_side(spec: mujoco.MjSpec, hand: str, side: str, palm_pos) -> SideLayout:
    base = spec.worldbody.add_body(name=f"{side}/base", pos=list(palm_pos))
    wrist = base.add_body(name=f"{side}/wrist")
    joints = []
    for axis, jtype, vec in WRIST_AXES:
        name = f"{side}/wrist/{axis}"
        lo, hi = WRIST_RANGE[axis]
        wrist.add_joint(name=name, type=mujoco.mjtJoint(jtype), axis=list(vec),
                        range=[lo, hi], armature=0.01, damping=0.0)
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=WRIST_KP[jtype], dampratio=1.0)
        act.ctrlrange = [lo, hi]
        act.forcerange = [-WRIST_FORCE[jtype], WRIST_FORCE[jtype]]
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        joints.append(name)
    hand_joints, tips, tip_sites, root = _attach_hand(spec, wrist, hand, side,
                                                      HOME_PALM_ROT, np.zeros(3))
    _mark_robot(wrist)
    return SideLayout(side, f"{side}/base", f"{side}/hand/palm", tuple(tips),
                      tuple(tip_sites), tuple(joints), tuple(hand_joints), tuple(palm_pos),
                      {j: 0.0 for j in joints}, root)


def _add_arm_side(spec: mujoco.MjSpec, arm: str, hand: str, side: str, palm_pos,
                  home: dict[str, float] | None) -> SideLayout:
    info = ARMS[arm]
    geo = hand_geometry(hand, side)
    # H sits on the tool axis just far enough out that the whole hand is beyond the
    # flange face, so it cannot cut into the wrist links (their contacts are filtered).
    tool_axis = info.hand_rot[2]  # in H
    standoff = geo.extent_behind(tool_axis)
    flange_x = palm_pos[0] - standoff * (HOME_PALM_ROT @ tool_axis)[0]
    base_x = flange_x - info.flange_reach
    # Level with the table top, raised with the home for a raised workspace; the pedestal
    # stands on the floor, or on the table where the workspace brings the base over it.
    base_z = TABLE_TOP_Z + (palm_pos[2] - HOME_PALM_Z)
    base_pos = [base_x, palm_pos[1], base_z]
    base = spec.worldbody.add_body(name=f"{side}/base", pos=base_pos)
    on_table = abs(base_x) < TABLE_HALF_SIZE[0] and abs(palm_pos[1]) < TABLE_HALF_SIZE[1]
    pedestal = base_z - (TABLE_TOP_Z if on_table else 0.0)
    if pedestal > 0.0:
        base.add_geom(name=f"{side}/pedestal", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                      size=[0.09, pedestal / 2, 0], pos=[0, 0, -pedestal / 2],
                      rgba=[0.25, 0.25, 0.28, 1])
    arm_spec = robot_spec(info.collection, info.entry)
    for key in list(arm_spec.keys):
        arm_spec.delete(key)
    _adopt_options(arm_spec, spec)
    for joint in arm_spec.joints:
        joint.armature = max(joint.armature, info.armature)
    prefix = f"{side}/arm/"
    arm_joints = [prefix + j.name for j in arm_spec.joints]
    arm_root = prefix + arm_spec.worldbody.first_body().name
    spec.attach(arm_spec, prefix=prefix, frame=base.add_frame())
    site = spec.site(prefix + "attachment_site")
    flange = site.parent
    mount = flange.add_body(name=f"{side}/mount", pos=list(site.pos), quat=list(site.quat))
    palm_in_flange = np.array([0.0, 0.0, standoff])
    hand_joints, tips, tip_sites, root = _attach_hand(spec, mount, hand, side,
                                                      info.hand_rot, palm_in_flange)
    _mark_robot(spec.body(arm_root))
    home_q = home if home is not None else dict(zip(arm_joints, info.seed_qpos, strict=True))
    return SideLayout(side, f"{side}/base", f"{side}/hand/palm", tuple(tips),
                      tuple(tip_sites), tuple(arm_joints), tuple(hand_joints),
                      tuple(palm_pos), home_q, root)


def _palm_home(name: EmbodimentName, side: str,
               workspace: tuple[float, float, float] = DEFAULT_WORKSPACE
               ) -> tuple[float, float, float]:
    """The hand frame's home position. An arm keeps the same pose relative to the task's
    workspace on every task (its home and base move with it), so what it reaches on the
    table centre it reaches wherever a task works, and its home hand is as far above a
    raised workspace as above the table; the floating wrist ignores it."""
    y = BIMANUAL_Y[side] if name.bimanual else 0.0
    if name.mount == "floating":
        return (HOME_PALM_X, y, HOME_PALM_Z)
    dx, dy, dz = (w - d for w, d in zip(workspace, DEFAULT_WORKSPACE, strict=True))
    return (HOME_PALM_X + dx, y + dy, HOME_PALM_Z + dz)


def set_joints(model: mujoco.MjModel, data: mujoco.MjData, values: dict[str, float]) -> None:
    """Write named joints' positions into `data.qpos`."""
    for joint, q in values.items():
        data.qpos[model.joint(joint).qposadr[0]] = q


def _arm_only(arm: str, hand: str, side: str, home: dict[str, float] | None
              ) -> tuple[mujoco.MjModel, mujoco.MjData, SideLayout]:
    """A robot-only model of one arm side at the default home palm, its joints at `home`
    (None: the arm's IK seed)."""
    spec = new_spec()
    layout = _add_arm_side(spec, arm, hand, side, DEFAULT_HOME_PALM, home)
    model = spec.compile()
    data = mujoco.MjData(model)
    set_joints(model, data, layout.home_qpos)
    return model, data, layout


@functools.cache
def arm_home(arm: str, hand: str, side: str) -> tuple[tuple[str, float], ...]:
    """Arm joint angles that put the hand frame at its home pose (palm down, fingers +x).

    Solved once per (arm, hand, side) by IK on a robot-only model; the relative geometry
    is the same for every offset, so y = 0 serves the bimanual sides and the default
    workspace every task's (`_palm_home`).
    """
    model, data, layout = _arm_only(arm, hand, side, None)
    q, err = solve_site_pose(model, data, layout.palm_site, list(layout.mount_joints),
                             np.array(DEFAULT_HOME_PALM), HOME_PALM_ROT, iterations=500)
    if err > 1e-3:
        raise RuntimeError(f"no home pose for arm {arm} with hand {hand} ({side}): "
                           f"IK error {err:.4f}; adjust ArmSpec.seed_qpos or flange_reach")
    return tuple((j, float(v)) for j, v in zip(layout.mount_joints, q, strict=True))


@functools.cache
def arm_servo_damping(arm: str, hand: str, side: str) -> tuple[tuple[str, float], ...]:
    """(actuator, kv) for each arm joint servo: `ArmSpec.damping_ratio` of critical
    damping for the joint's inertia at the home pose with the hand on, less the joint's
    own damping (solved once per (arm, hand, side) on a robot-only model); none without
    a ratio (the model's gains stay)."""
    ratio = ARMS[arm].damping_ratio
    if ratio is None:
        return ()
    model, data, layout = _arm_only(arm, hand, side, dict(arm_home(arm, hand, side)))
    mujoco.mj_forward(model, data)
    inertia = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, inertia)
    out = []
    for a in range(model.nu):
        joint = model.actuator_trnid[a, 0]
        if (model.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT
                or model.joint(joint).name not in layout.mount_joints):
            continue
        dof = model.jnt_dofadr[joint]
        critical = 2.0 * np.sqrt(model.actuator_gainprm[a, 0] * inertia[dof, dof])
        kv = ratio * critical - model.dof_damping[dof]
        out.append((model.actuator(a).name, float(max(kv, 0.0))))
    return tuple(out)


def _damp_arm_servos(spec: mujoco.MjSpec, damping: tuple[tuple[str, float], ...]) -> None:
    """Give the arm's position servos their velocity gains (`arm_servo_damping`)."""
    for name, kv in damping:
        act = spec.actuator(name)
        bias = np.array(act.biasprm)
        bias[2] = -kv
        act.biasprm = bias


def add_embodiment(spec: mujoco.MjSpec, embodiment: str,
                   workspace: tuple[float, float, float] = DEFAULT_WORKSPACE) -> EmbodimentPlan:
    """Add an embodiment to `spec`, its arms placed for a task working around `workspace`
    (`DEFAULT_WORKSPACE`, `_palm_home`); return its layout and per-actuator pose targets."""
    name = parse_embodiment(embodiment)
    sides: dict[str, SideLayout] = {}
    targets: dict[str, dict[str, float]] = {s: {} for s in SYNERGIES}
    hand_qpos: dict[str, float] = {}
    for side in name.sides:
        palm = _palm_home(name, side, workspace)
        if name.mount == "floating":
            layout = _add_floating_side(spec, name.hand, side, palm)
        else:
            home = dict(arm_home(name.mount, name.hand, side))
            layout = _add_arm_side(spec, name.mount, name.hand, side, palm, home)
            _damp_arm_servos(spec, arm_servo_damping(name.mount, name.hand, side))
        sides[side] = layout
        geo = hand_geometry(name.hand, side)
        for pose in targets:
            for act, value in zip(geo.actuators, geo.synergies[pose], strict=True):
                targets[pose][f"{side}/hand/{act}"] = float(value)
        hand_qpos.update({f"{side}/hand/{j}": q for j, q in geo.open_qpos.items()})
    return EmbodimentPlan(name, sides, targets, hand_qpos)


def robot_at_home(embodiment: str, workspace: tuple[float, float, float] = DEFAULT_WORKSPACE
                  ) -> tuple[mujoco.MjModel, mujoco.MjData, EmbodimentPlan]:
    """A robot-only model of `embodiment`, placed for `workspace` as a task's scene places
    it, every joint at home and its kinematics computed: where IK and reach checks start."""
    spec = new_spec()
    plan = add_embodiment(spec, embodiment, workspace)
    model = spec.compile()
    data = mujoco.MjData(model)
    for layout in plan.sides.values():
        set_joints(model, data, layout.home_qpos)
    mujoco.mj_kinematics(model, data)
    return model, data, plan
