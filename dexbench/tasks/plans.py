"""Expert plans as data: how a task's scripted expert solves it, written next to the task.

A task's `expert` is one of these plan kinds (or a `SequencePlan` of them);
`dexbench.experts` holds one closed-loop script per kind and runs the plan on any hand
and mount. Plans name objects by their keys in the task's `objects` and points by
their `ObjectInfo.points` names, so object geometry is never restated here: a
`PointRef` is a point name, a point name and an offset in that point's body frame, or
an offset from the object's root.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from dexbench.assets.objects import ObjectInfo, Vec3
from dexbench.envs.dex_env import DexEnv

PointRef = str | Vec3 | tuple[str, Vec3]
EnvFn = Callable[[DexEnv], np.ndarray]
# A `HoldActuatePlan` side: each episode, the hand whose arm reaches the push better
# (`dexbench.experts.either_hand`); the right one on a floating pair, where both do.
EITHER = "either"


def locate(objects: Mapping[str, ObjectInfo], obj: str, ref: PointRef) -> tuple[str, Vec3]:
    """(body, point in its frame) of a `PointRef` on object `obj`."""
    info = objects[obj]
    if isinstance(ref, str):
        return info.points[ref]
    if isinstance(ref[0], str):
        body, base = info.points[ref[0]]
        return body, tuple(float(b + o) for b, o in zip(base, ref[1], strict=True))
    return info.root, tuple(float(v) for v in ref)


def body_yaw(quat: np.ndarray) -> np.ndarray:
    """(N,) yaw about world z of bodies with orientations `quat` (N, 4) (w, x, y, z)."""
    w, x, y, z = quat.T
    return np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles (rad) wrapped into [-pi, pi)."""
    return (angle + np.pi) % (2 * np.pi) - np.pi


def turnable_offset(body: str, final_yaw: EnvFn, offsets: tuple[float, float]) -> EnvFn:
    """Grasp yaw offsets (N,) from `body`'s yaw, one of two `offsets` (rad): the one from
    which the hand's turn that brings the body to `final_yaw(env)` keeps the hand's yaw
    within +-pi (a floating wrist's yaw joint stops there)."""
    def offset(env: DexEnv) -> np.ndarray:
        yaw = body_yaw(env.view.body_quat(body).cpu().numpy())
        turn = wrap(final_yaw(env) - yaw)
        return np.where(np.abs(wrap(yaw + offsets[0]) + turn) < np.pi, *offsets)
    return offset


@dataclass(frozen=True)
class HandleBetween:
    """Grasp yaw offsets (N,) from `body`'s yaw (its handle along body +x) that put the
    handle between `lo` and `hi` (rad, `lo` < `hi` < `lo` + 2 pi; from the fingers'
    direction towards the palm's facing direction; the handle cannot lie between the
    palm and the vessel), the fingers along world +x where the handle allows it, else
    the nearer end: a hand reaching far round to the side or back towards its own base
    turns the vessel poorly. A `GraspPlan.yaw_offset`; the range stays readable
    (`clear`), so a pour that turns the grasp keeps the handle where it may lie."""

    body: str
    lo: float
    hi: float

    def clear(self, rel: np.ndarray) -> np.ndarray:
        """Whether a handle at `rel` (rad, measured as above) lies between `lo` and `hi`."""
        return (np.asarray(rel) - self.lo) % (2 * np.pi) <= self.hi - self.lo

    def __call__(self, env: DexEnv) -> np.ndarray:
        yaw = body_yaw(env.view.body_quat(self.body).cpu().numpy())
        past_lo = (yaw - self.lo) % (2 * np.pi)
        nearer_lo = past_lo - (self.hi - self.lo) > 2 * np.pi - past_lo
        rel = np.where(self.clear(yaw), self.lo + past_lo,
                       np.where(nearer_lo, self.lo, self.hi))
        return -rel


def task_goal(env: DexEnv) -> np.ndarray:
    """The goal point the task sampled this episode."""
    return env.view.goal[:, :3].cpu().numpy()


def object_point(obj: str, point: str, above: float = 0.0) -> EnvFn:
    """Where object `obj`'s point `point` is now, `above` (m) higher: a target that is
    another object (the mug a kettle pours into)."""
    def at(env: DexEnv) -> np.ndarray:
        pos = env.view.point_pos(*env.task.objects[obj].points[point]).cpu().numpy()
        return pos + np.array([0.0, 0.0, above])
    return at


@dataclass(frozen=True)
class GraspPlan:
    """Grasp-and-move: where and how to hold object `obj`, and where to take it.

    `point` is the grasp point, `shift` moves it in the hand frame from where the hand
    holds a 5 cm cube (its `grasp_offset`) to suit the object's size; `side` grasps
    (upright cylinders) hold it in a handshake pose instead of from above, `pitch` (rad)
    tilts the fingers down from the top grasp (90 deg: hanging, palm towards the object,
    to hook a handle). `yaw` is "box" (the object's face yaw nearest to the approach),
    "body" (the object's yaw) or "none", turned further by `yaw_offset` (rad, or
    `yaw_offset(env) -> (N,)`). `settle` (s) replaces the closed hand's default wait;
    the fingers close `squeeze` times as far as `synergy` (within the actuators' ranges):
    a firmer hold on a thin or heavy-ended handle. With `standoff` (m) the grasp moves
    along the palm normal until the open hand stands that far clear of the object (each
    hand by its own size); without, `shift` alone places it. `hand_shift` names the
    kind of grasp for which a hand adds its own correction to `shift`
    (`HandSpec.shifts`: "vessel", "rim", "tool"): the plans' shifts are the Shadow hand's.
    After the grasp the object is lifted `lift` metres, or, with `target(env) -> (N, 3)`,
    carried until its `goal_point` is there; with `release`, the hand then opens and
    backs off (placing), as it does whenever `let_go(env) -> (N,) bool` holds while
    carrying. `carry_high` lifts the object over the table's clutter until it is above
    its target (off for pulling). With `wait(env) -> (N,) bool` the open hand stays
    where it is until that holds before it sets out (a hand taking the object from the
    other hand waits until it is set down). A hand letting go backs off `back_off` (m)
    away from its palm side (up from a top grasp): far enough for another hand to come
    in over the object. With `commanded_hand` the mount's IK takes the hand's own joints
    (a wrist) at their commanded targets, not as measured (`ActionAdapter`): a heavy
    tool swings a weak wrist, and chasing each swing with the mount flings it out.
    `arrive` (m) replaces how close the palm must come to the grasp pose to close (a
    floating hand that sags a little short of it otherwise closes only after the
    descent's time-out), and `carry_speed` (m/s) the careful speed of the descent and
    the carry (an object held firmly can be carried faster). None keeps the script's.
    """

    obj: str
    point: PointRef = (0.0, 0.0, 0.0)
    shift: Vec3 = (0.0, 0.0, 0.0)
    yaw: str = "box"
    yaw_offset: float | EnvFn = 0.0
    side: bool = False
    pitch: float = 0.0
    synergy: str = "power"
    lift: float = 0.28
    target: EnvFn | None = None
    goal_point: PointRef = (0.0, 0.0, 0.0)
    release: bool = False
    let_go: EnvFn | None = None
    carry_high: bool = True
    settle: float | None = None
    squeeze: float = 1.0
    standoff: float | None = None
    wait: EnvFn | None = None
    back_off: float = 0.06
    commanded_hand: bool = False
    arrive: float | None = None
    carry_speed: float | None = None
    hand_shift: str | None = None


@dataclass(frozen=True)
class SwingPlan:
    """`grasp` hooks the handle (its `point`) of a part on the hinge `joint` and pulls it
    along the hinge's arc towards the joint's upper limit for `direction` +1 (a door, a
    lid): the carried handle is led `lead` (m) ahead along the arc, and the hand turns
    with the part so its hook stays square to the handle; at the limit it holds still.
    With `latch` (the hinge joint of a handle on the part: a door's lever that draws its
    latch), the hooked handle is first turned the same way about that joint, towards its
    upper limit, until it has covered `latch_turn` of its travel; the part then swings
    with the hand keeping the handle turned."""

    grasp: GraspPlan
    joint: str
    direction: float = 1.0
    lead: float = 0.08
    latch: str | None = None
    latch_turn: float = 0.9


@dataclass(frozen=True)
class BothHandsPlan:
    """Each hand runs its own plan at the same time (`hands`: side -> a plan of a kind
    whose script takes a side, e.g. `GraspPlan`, `SwingPlan`): two doors, one per hand.
    Finished once every hand's plan is."""

    hands: Mapping[str, Any]


@dataclass(frozen=True)
class PinchPlan:
    """Pick a thin object (a pen, a stick lying on the table) off its support between the
    thumb and index tips: the hand's `synergy` closes those two on each other, the other
    fingers kept clear of the support.

    The hand comes down palm-down (rolled so the two tips are level) with the fingers
    `preshape` of the way closed, the line from the thumb tip to the index tip across the
    object's `axis`, the tips straddling `point` (moved by `shift`, hand frame), their
    lowest points `depth` (m) below it (an object lying on the table: its height over
    the table, so the tips sweep in on it). The hand moves with the closing fingers to
    keep the tips there. The fingers close `squeeze` times as far as `synergy` (within
    the actuators' ranges: weak fingers press harder), wait `settle` (s), and the hand
    rises `lift` (m) and holds; a dropped object is grasped again. The tips are levelled
    as they stand at closure `level` (default `preshape`): a thumb that rises as it closes,
    levelled nearer where the tips meet, reaches a thin object's side, not its top. Given
    the object's `width` (m) across the tips instead, they are levelled where they stand
    that far apart, wherever that is on each hand's closing. With `target(env) -> (N, 3)`
    the risen hand then carries the object until its `goal_point` (default: the pinched
    point) is there, and holds it (a thin object pulled out of a container). An object
    that `hangs` is turned end-down next (a pen into a holder): a hand whose spec says so
    (`HandSpec.hang_back`) takes of the two grasps the one with its longer part back
    towards the wrist."""

    obj: str
    point: PointRef = (0.0, 0.0, 0.0)
    axis: str = "long"
    synergy: str = "tip_pinch"
    preshape: float = 0.5
    depth: float = 0.0
    shift: Vec3 = (0.0, 0.0, 0.0)
    squeeze: float = 1.0
    settle: float = 0.5
    lift: float = 0.1
    level: float | None = None
    width: float | None = None
    target: EnvFn | None = None
    goal_point: PointRef | None = None
    hangs: bool = False


@dataclass(frozen=True)
class LevelPlan:
    """`grasp`, whose carry also pitches the hand fingers-down (up to `max_angle` rad, at
    `rate` rad/s) as far as keeps the held object's `axis` tilted `tilt` deg while
    `active(env)` holds: an object held by one end sags."""

    grasp: GraspPlan
    axis: str
    tilt: float
    active: EnvFn
    rate: float = 0.5
    max_angle: float = 0.8


@dataclass(frozen=True)
class PressPlan:
    """Press `point` of `obj` from above; `with_fingers` presses with the mean fingertip
    rather than the palm; `yaw` turns the fingers (rad) from the point's body x axis,
    `pitch` tilts them down (rad) so only the tips touch. `keep_off` names a body (with
    the bodies below it) no fingertip may rest on, a part beside the point that has to
    move (the scissors' other ring): a hand whose spread fingers would put a tip on it
    presses with one tip instead, or turns, whichever keeps the tips clearest of it."""

    obj: str
    point: PointRef
    with_fingers: bool = True
    yaw: float = 0.0
    pitch: float = 0.0
    keep_off: str | None = None


@dataclass(frozen=True)
class TurnPlan:
    """Push the `tip` point of `obj`'s hinged part along its arc, about `obj`'s joint
    `hinge` (default: its only joint), towards the joint's upper limit for `direction`
    +1 (lower for -1; for 0, whichever end leaves the tip nearer the hand's start, for
    parts that may go either way). With `pitch` (rad) the hand is palm-down, fingers
    along the object root's x axis tilted down by `pitch`, and comes in from `approach`
    (a direction in the root's frame, its length scaling the hover height); without, it
    hangs its fingers beside the tip and comes down from `approach` (above), and `lean`
    (rad) swings the hanging fingers out along the tip's radius (negative: in towards
    the hinge; pads still facing the push): an arm's hand then reaches a tip far out
    over the table. With `period` (rad) the tip repeats that often round the hinge (a
    cap's fins): the hand pushes one copy through a period, lifts and comes down behind
    the next, stroke after stroke. `push_speed` (m/s) limits the hand while it pushes.
    `under` (m, with `pitch`) slides the pads that far past the tip along the fingers, so
    a lid's edge rests nearer the knuckles: soft fingers (Wuji's) bend away under a heavy
    lid pushed at their tips, but hold it on a short lever arm."""

    obj: str
    tip: PointRef
    hinge: str | None = None
    direction: float = 1.0
    pitch: float | None = None
    approach: Vec3 = (0.0, 0.0, 1.0)
    lean: float = 0.0
    period: float | None = None
    push_speed: float = 0.1
    under: float = 0.0


@dataclass(frozen=True)
class PushPlan:
    """Push the flat block `obj` (footprint `rects`, (cx, cy, hx, hy) in its frame, and
    `height`) to the planar pose `goal(env) -> (N, 3)` (x, y, yaw) with one fingertip;
    `done(env) -> (N,) bool`: close enough, the hand lifts off and waits."""

    obj: str
    rects: Sequence[tuple[float, float, float, float]]
    height: float
    goal: EnvFn
    done: EnvFn


@dataclass(frozen=True)
class PathPushPlan:
    """Push the ball `obj` with one fingertip along the polyline `path(env) -> (N, K, 3)`
    (a ramp's centre line, between obstacles), steering it back onto the line as it
    strays; `done(env) -> (N,) bool`: far enough, the hand lifts off and waits."""

    obj: str
    path: EnvFn
    done: EnvFn


@dataclass(frozen=True)
class PivotPlan:
    """Stand the flat object `obj` up about its edge `pivot`, held by a support (a wall,
    a stop) on the far side, by lifting its opposite edge `end` round it: the open hand
    turns with the object, fingers down the end face and pads towards the pivot, and its
    fingertips push on the end face towards the pivot and up along the arc (friction
    carries the end round). `done(env) -> (N,) bool`: up far enough, the hand holds
    still."""

    obj: str
    end: PointRef
    pivot: PointRef
    done: EnvFn


@dataclass(frozen=True)
class TwoHandPlan:
    """Both hands hook one grip point of `obj` each (`grips`: side -> point name) and lift
    it together. `shift` moves the grip point in the right hand's frame from where the
    hand holds a 5 cm cube (mirrored for a mirrored hand); `pull` (m) is how far the
    closed hands draw back along their fingers, `lift` (m) how high they then rise.
    With `press` (a closed box: no rim to hook) each open palm faces its grip point, a
    side face's middle, fingers down to just above the object's base, its pressing face
    (`palm_face`: the palm's and fingers' outermost parts, thumb aside) centred on the
    point and `shift`'s z (m) out from it (on an arm, turned about the palm normal where
    the wrist cannot hang the fingers straight down), and pushes `pull` m on (so `pull`
    less that z into the object): the two pushes squeeze the object between the palms.
    With `hook` each
    hand closes only as far as its fingertips reach deepest (a hook) and is placed, before
    `shift`, by where they then end: just past the grip point (a rim's middle), level with
    it, centred across the fingers. Placed by its cube grasp instead, a hand whose fingers
    are shorter or curl further than that grasp's geometry suggests closes them on or
    outside the rim, under the object, and flips it."""

    obj: str
    grips: Mapping[str, str]
    shift: Vec3 = (0.0, 0.0, 0.0)
    pull: float = 0.025
    lift: float = 0.27
    press: bool = False
    hook: bool = False


@dataclass(frozen=True)
class HoldActuatePlan:
    """One hand (`side`) pushes point `point` of `obj` along its joint `joint`'s motion
    (the arc of a hinge, the line of a slide) towards the joint's upper limit for
    `direction` +1, while the other hand runs `hold` (e.g. a `PressPlan` pinning the
    object down; None: one hand is enough). The pusher waits until the holder presses.
    With `yaw` (rad, from `obj`'s x axis) the pushing hand is palm-down, its fingers
    tilted down by `pitch`, coming in from `approach` (a direction in `obj`'s frame);
    without, its fingers hang beside the point, pads facing the push. Once the joint has
    covered `done` of its travel the hand stops there, or, with `release`, backs off to
    where it came in from (a holding hand keeps holding); then it is finished (for a
    `SequencePlan`). Without `hold`, the other hand waits out of the way, then, with
    `then`, runs that plan once the joint is done (picks the object up with its part
    moved) and the pusher is finished when it is. `side` `EITHER` picks the pushing hand
    per episode, for an object that may lie on either hand's side of the table."""

    obj: str
    joint: str
    point: PointRef
    direction: float = 1.0
    yaw: float | None = None
    pitch: float = 0.0
    approach: Vec3 = (0.0, 0.0, 1.0)
    hold: PressPlan | None = None
    side: str = "right"
    done: float = 1.0
    release: bool = False
    then: Any = None


@dataclass(frozen=True)
class InsertPlan:
    """Insert the held `peg` (its `head` point and `shaft` axis) into `hole` (its
    `entrance` and `target` points and `bore` axis, pointing out of the hole); the hand
    keeps closing `synergy` `squeeze` times as far (as the grasp that holds the peg).
    A keyed fit (a hex nut onto a hex seat) names `key`: (peg axis, hole axis, period
    in rad): lining up also turns the peg about the bore until its axis matches the
    hole's, modulo the period, before it pushes in."""

    peg: str
    hole: str
    head: str = "head"
    shaft: str = "shaft"
    entrance: str = "entrance"
    target: str = "target"
    bore: str = "bore"
    synergy: str = "power"
    squeeze: float = 1.0
    key: tuple[str, str, float] | None = None


@dataclass(frozen=True)
class TwistPlan:
    """Turn a part about the vertical through `obj`'s `point` by regrasping, as fingers
    run a nut down a bolt: come down palm-down over the point (fingers along world yaw
    `yaw`, the grasp moved by `shift` in the hand frame as in `GraspPlan`), close
    `synergy`, turn the hand by `stroke` (rad; negative: clockwise from above) at
    `turn_rate` following the part down, open, rise and come back for the next stroke;
    stroke after stroke until the episode ends."""

    obj: str
    point: PointRef = (0.0, 0.0, 0.0)
    stroke: float = -1.5
    yaw: float = 0.75
    shift: Vec3 = (0.0, 0.0, 0.0)
    synergy: str = "power"
    turn_rate: float = 2.5


@dataclass(frozen=True)
class PourPlan:
    """`grasp` holds and carries the vessel (its `goal_point`: the rim). Once the hand has
    risen `clearance` (m) it turns, at `turn_rate` (rad/s), by `tilt` (rad) about `about`
    (hand frame; z: the palm normal). The fingers close `squeeze` times as far as
    `grasp.synergy` (within the actuators' ranges), but the actuators matching a regex
    of `overrides` go to its target instead. `grasp_turn` (rad, about `about` too) is
    already there at the grasp; `tilt` is the whole turn, `grasp_turn` included. The
    actuators matching a regex of `open_overrides` go to its target in the open hand (the
    approach): a thumb standing off the palm would knock a tall vessel over on the way in.
    With `tip` (deg), a vessel whose "up" axis is tipped less than that from upright once
    the turn has reached `tilt` is turned on, up to `further` (rad) past it: how far a
    held vessel tips for a given turn depends on the grip, a weak one (the Shadow
    hand's) lets it settle further over in the fingers, a firm one (Sharpa's, Wuji's)
    holds it at the hand's own turn, short of the pour. (Stopping the turn short of
    `tilt` instead drops it from a hand that tips it early, LEAP's: it lies in the
    fingers only once the hand is turned over.)
    A `round_body` vessel (a cup, a can: round about its vertical axis) may be held from any
    side: a hand whose mount grossly misses the plan's grasp or pour (an arm's reach and
    wrist limits) takes the turn about that axis its mount reaches best; one whose grasp
    yaw is a `HandleBetween` (the mug) only the turns that keep its handle in that range."""

    grasp: GraspPlan
    tilt: float
    clearance: float = 0.05
    turn_rate: float = 1.5
    about: Vec3 = (0.0, 0.0, 1.0)
    squeeze: float = 1.0
    overrides: tuple[tuple[str, float], ...] = ()
    grasp_turn: float = 0.0
    open_overrides: tuple[tuple[str, float], ...] = ()
    tip: float | None = None
    further: float = 0.0
    round_body: bool = False


@dataclass(frozen=True)
class StrikePlan:
    """`grasp` holds a tool (its target and goal point are the script's) and carries its
    `face` point `hover` (m) above point `at` of object `on`; then presses the face down
    onto it, the command `depth` (m) below it, for `press` (s), rises back and presses
    again until `done(env) -> (N,) bool` (a nail driven home), then stays hovering."""

    grasp: GraspPlan
    face: PointRef
    on: str
    at: PointRef
    done: EnvFn
    hover: float = 0.04
    depth: float = 0.03
    press: float = 0.5


@dataclass(frozen=True)
class ReachPlan:
    """Move the open hand to `target(env, start) -> (N, 3)`, `start` being where the palm
    was when the step began. Without `yaw` the palm goes there keeping its orientation;
    with it, the hand turns palm-down, fingers along `yaw` (rad) tilted down by `pitch`,
    and its finger tips (their mean, thumb left out) go there. Done once arrived.
    `speed` (m/s) replaces the script's: a long move through free space in a task with
    a tight horizon."""

    target: Callable[[DexEnv, np.ndarray], np.ndarray]
    yaw: float | None = None
    pitch: float = 0.0
    speed: float | None = None


@dataclass(frozen=True)
class StackItem:
    """How the script picks up one shape and stacks it.

    `point` (body frame) and `shift` (hand frame) place the top-down grasp closing
    `synergy`, as in `GraspPlan`; `yaw` is "box" (faces, folded by 90 deg), "body" (its
    x axis, folded by 180 deg, turned by `yaw_offset`) or "none": the fingers' heading.
    `base` ranks flat-topped shapes as the stack's bottom (lower first; None: round,
    nothing stays on it); `period` is the yaw symmetry (rad) to line it up on the base
    (None: any yaw will do), `across` turns its x axis across the side grasp's fingers.
    """

    synergy: str = "power"
    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    shift: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw: str = "none"
    yaw_offset: float = 0.0
    base: int | None = None
    period: float | None = None
    across: bool = False


@dataclass(frozen=True)
class StackLiftPlan:
    """Lift two of the task's `candidates` at once by stacking one on the other and
    lifting the stack in one side grasp; `items` says how to pick up and stack each
    shape; `side_ready` (hand name -> actuator suffix -> target) opens a hand for the
    side grasp."""

    candidates: Sequence[str]
    items: Mapping[str, StackItem]
    side_ready: Mapping[str, Mapping[str, float]] = field(default_factory=dict)


Until = Callable[[DexEnv, Any], np.ndarray]


@dataclass(frozen=True)
class Step:
    """One step of a sequence: `plan` runs until `until(env, its expert) -> (N,) bool`
    (default: its expert's `finished`) has held for `hold` seconds (a door pushed shut
    that must have stopped bouncing before the hand lets it be)."""

    plan: Any
    until: Until | None = None
    hold: float = 0.0


@dataclass(frozen=True)
class SequencePlan:
    """Steps run one after another per env, each handing over when its subgoal holds;
    the last step runs to the end. Where `restart(env, experts) -> (N,) bool` holds (a
    dropped object), an env starts over."""

    steps: tuple[Step, ...]
    restart: Callable[[DexEnv, Sequence[Any]], np.ndarray] | None = None
