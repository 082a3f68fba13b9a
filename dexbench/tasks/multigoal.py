"""Multi-goal composites: a primary task plus a rigid add-on object, generated.

The paper's 39 variants are every primary of `PRIMARIES` with every add-on of `ADDONS`
(but itself), composed by `MultiGoalTask` from two small tables: per primary, where the
add-on fits clear of its moving parts, when its state is done and stays so after the
hand lets go (or why it needs a second hand), per add-on its object and plan. The
expert is the primary's plan, let go once done, then the add-on's (a `SequencePlan`);
where the primary must be held while the add-on is up, each hand runs one
(`BothHandsPlan`: the right hand the primary, the left the add-on, on the table's left).
An episode lasts as long as the two tasks' own episodes together.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.dex_env import DexEnv
from dexbench.tasks.articulation import OpenDrawer
from dexbench.tasks.articulation_doors import OpenDoor
from dexbench.tasks.articulation_hinged import OpenMicrowave
from dexbench.tasks.articulation_lids import GraspPot, LiftLid
from dexbench.tasks.articulation_turn import GraspBucket, RotateKnob
from dexbench.tasks.catalog import register
from dexbench.tasks.functional import FunctionalPourCan, FunctionalPourMug
from dexbench.tasks.plans import (
    BothHandsPlan,
    GraspPlan,
    PourPlan,
    ReachPlan,
    SequencePlan,
    Step,
    SwingPlan,
)
from dexbench.tasks.primitive import PickUpStick, PushButton, RelocateSphere, TurnOnSwitch
from dexbench.tasks.templates import ADDON_LIFT, MultiGoalTask, Placement, TabletopTask

Done = Callable[[DexEnv], np.ndarray]

# Add-on regions (its centre, world m): beside the primary, on the side its moving parts
# never sweep, far enough that the widest add-on's footprint (the mug's, 7.4 cm round its
# handle) stays clear of them (`tests/test_tasks_multigoal.py` checks it over many
# resets) and a hand grasping it from the side (palm towards the primary) has room;
# near enough that the hand's wrist reaches that far. The doors swing out on the robot's
# left, so their add-on stands on its right; the rest on its left (the left hand's side,
# where a second hand takes the add-on).
LEFT = Placement((-0.15, 0.05), (0.42, 0.50))
RIGHT_OF_DOOR = Placement((-0.25, -0.05), (-0.46, -0.38))
TWO_HANDS = ("Needs the bimanual floating Shadow hand: the right hand does the primary, "
             "the left lifts the add-on, as one hand cannot do both at once here: ")


def joint_done(fraction: float, still: float | None = None) -> Done:
    """The primary's joint covers `fraction` of its travel from reset (and, with `still`,
    turns slower than that, rad/s: a dial pushed onto its stop rebounds off it if let go
    while still moving)."""
    def done(env: DexEnv) -> np.ndarray:
        task = env.task.primary  # type: ignore[attr-defined]
        out = (task.joint_progress(env.view, task.joint) >= fraction).cpu().numpy()
        if still is not None:
            dof = env.scene.model.joint(task.joint).dofadr[0]
            out &= (env.sim.field("qvel")[:, dof].abs() < still).cpu().numpy()
        return out
    return done


@dataclass(frozen=True)
class Primary:
    """How a primary task composes. `done`: its state is reached and stays after the hand
    lets go (then the hand goes on to the add-on); with `two_hands` (the reason) it does
    not, and each hand takes one goal. In between, the open hand rises straight up, turned
    as it is (its fingers drag nothing along), until its palm is `clear` (m) above the
    table (a door left open stands between its handle and the add-on), then goes over to
    above the add-on turning palm down, fingers forward, as at the start: the add-on's
    grasp then turns the wrist as in its own task (from a hanging or leaning hand, the
    wrist's roll would reach its stop). `placement` narrows the primary's own region
    where the add-on needs the rest (its hand's half of the table)."""

    cls: type[TabletopTask]
    addon_at: Placement
    done: Done | None = None
    two_hands: str | None = None
    placement: Placement | None = None
    clear: float = 0.25


@dataclass(frozen=True)
class Addon:
    """An add-on: its task, the object lifted, what the instruction calls it, and the plan
    that lifts it (its own task's grasp, carried nowhere: it stays lifted)."""

    cls: type[TabletopTask]
    obj: str
    noun: str
    plan: Any


def lift_only[P: (GraspPlan, PourPlan)](plan: P) -> P:
    """An add-on's own plan without its target: it lifts the object and holds it there
    (a pour holds it as for pouring, turned no further than at the grasp)."""
    if isinstance(plan, PourPlan):
        return dataclasses.replace(plan, tilt=plan.grasp_turn,
                                   grasp=dataclasses.replace(plan.grasp, target=None))
    return dataclasses.replace(plan, target=None)


# Each state below was checked to stay, the hand gone (`tests/test_tasks_multigoal.py`):
# the drawer and the doors where they are left, the lids and the bucket's bail once pushed past
# upright (they fall open onto their stops), the knob and the switch at their stops.
PRIMARIES: dict[str, Primary] = {
    "OpenMicrowave": Primary(OpenMicrowave, RIGHT_OF_DOOR, joint_done(0.9), clear=0.50),
    "OpenDoor": Primary(OpenDoor, RIGHT_OF_DOOR, joint_done(0.9), clear=0.64),
    "OpenDrawer": Primary(OpenDrawer, Placement((-0.20, 0.0), (0.52, 0.58)), joint_done(0.95),
                          clear=0.45),
    "LiftLid": Primary(LiftLid, LEFT, joint_done(0.95)),
    "GraspPot": Primary(GraspPot, LEFT, joint_done(0.95)),
    "PushButton": Primary(PushButton, Placement((-0.15, 0.05), (0.30, 0.42)), two_hands=(
        "the button springs back once let go, and a hand holding the add-on 0.15 m up "
        "cannot also press a cap 6 cm above the table (neither with its knuckles nor with "
        "the held object, which would then not be lifted)."),
        # Its own region's right half, turned within 45 deg: the housing is square, so
        # every pose it had (the palm presses along the housing's x, fingers away from
        # the left hand).
        placement=Placement((-0.05, 0.15), (-0.15, 0.0), (-math.pi / 4, math.pi / 4))),
    "RotateKnob": Primary(RotateKnob, LEFT, joint_done(0.97, still=0.05), clear=0.45),
    "TurnOnSwitch": Primary(TurnOnSwitch, LEFT, joint_done(0.8)),
    "GraspBucket": Primary(GraspBucket, LEFT, joint_done(0.6)),
    "PourMug": Primary(FunctionalPourMug, Placement((-0.10, 0.10), (0.30, 0.42)), two_hands=(
        "the mug is held up and poured at the goal while the add-on is lifted, two "
        "objects held apart at once; the mug stands on the table's right half."),
        placement=Placement((-0.10, 0.20), (-0.35, -0.05))),
}

ADDONS: dict[str, Addon] = {
    "PourCan": Addon(FunctionalPourCan, "can", "can", lift_only(FunctionalPourCan.expert)),
    "PickUpStick": Addon(PickUpStick, "stick", "stick", lift_only(PickUpStick.expert)),
    "PourMug": Addon(FunctionalPourMug, "mug", "mug", lift_only(FunctionalPourMug.expert)),
    "RelocateSphere": Addon(RelocateSphere, "sphere", "ball",
                            lift_only(RelocateSphere.expert)),
}


# `GraspExpert` places every hand by a right hand's `grasp_offset`: a left Shadow hand's
# top grasp is 2.6 cm over along the hand's y axis, that offset mirrored (as in
# BimanualHandover).
LEFT_SHADOW_SHIFT = 0.026


def for_left_hand(plan: Any) -> Any:
    """An add-on's plan for the left hand: a top grasp's point moved by the mirrored
    offset (a side grasp's hand y is vertical: it holds as it is)."""
    if isinstance(plan, GraspPlan) and not plan.side:
        x, y, z = plan.shift
        return dataclasses.replace(plan, shift=(x, y + LEFT_SHADOW_SHIFT, z))
    return plan


def _rise(height: float) -> Callable[[DexEnv, np.ndarray], np.ndarray]:
    """Straight above where the hand starts, `height` (m) above the table."""
    def up(env: DexEnv, start: np.ndarray) -> np.ndarray:
        return np.concatenate([start[:, :2], np.full((len(start), 1), TABLE_TOP_Z + height)],
                              axis=1)
    return up


def _over(obj: str, height: float) -> Callable[[DexEnv, np.ndarray], np.ndarray]:
    """Above object `obj`, `height` (m) above the table."""
    def over(env: DexEnv, start: np.ndarray) -> np.ndarray:
        at = env.view.body_pos(env.task.objects[obj].root).cpu().numpy()
        return np.concatenate([at[:, :2], np.full((len(at), 1), TABLE_TOP_Z + height)], axis=1)
    return over


def compose(spec: Primary, addon: Addon) -> Any:
    """The variant's expert: both plans side by side (two hands), or the primary's until
    done (a grasp lets go then), then the add-on's."""
    plan = spec.cls.expert
    if spec.two_hands is not None:
        return BothHandsPlan({"right": plan, "left": for_left_hand(addon.plan)})
    assert spec.done is not None
    let_go = spec.done
    if isinstance(plan, SwingPlan):
        first = Step(dataclasses.replace(plan, grasp=dataclasses.replace(plan.grasp,
                                                                         let_go=let_go)))
    elif isinstance(plan, GraspPlan):
        first = Step(dataclasses.replace(plan, let_go=let_go))
    else:  # pushing or pressing plans hold no grip: the step ends once done
        first = Step(plan, until=lambda env, _: let_go(env))
    return SequencePlan((first, Step(ReachPlan(_rise(spec.clear))),
                         Step(ReachPlan(_over(addon.obj, spec.clear), yaw=0.0)),
                         Step(addon.plan)))


def _sentence(text: str) -> str:
    """`text` without its final full stop, its first letter lower-case."""
    text = text.rstrip(".")
    return text[0].lower() + text[1:]


class GeneratedMultiGoal(MultiGoalTask):
    """A generated variant; `primary_placement` replaces the primary's own region."""

    primary_placement: ClassVar[Placement | None] = None

    def __init__(self) -> None:
        super().__init__()
        if self.primary_placement is not None:
            first = next(iter(self.primary.placements))
            self.placements = {**self.placements, first: self.primary_placement}


def make_variant(primary: str, addon: str) -> type[MultiGoalTask]:
    """The class of variant `<primary>_<addon>`."""
    spec, add = PRIMARIES[primary], ADDONS[addon]
    name = f"{primary}_{addon}"
    cls = spec.cls
    attrs: dict[str, Any] = {
        "name": name,
        "instruction": f"{cls.instruction.rstrip('.')} and lift the {add.noun}.",
        "description": (f"{cls.description.rstrip('.')}; and lift the {add.obj}, both in "
                        "one episode."),
        "success_text": (f"At the same time: {_sentence(cls.success_text)}; and the "
                         f"{add.obj} is lifted at least {ADDON_LIFT:g} m above its reset "
                         "height."),
        "episode_seconds": cls.episode_seconds + add.cls.episode_seconds,
        "primary_cls": cls,
        "addon_cls": add.cls,
        "addon_object": add.obj,
        "addon_placement": spec.addon_at,
        "primary_placement": spec.placement,
        "expert": compose(spec, add),
        "deviations": tuple(dict.fromkeys(
            n for c in reversed(cls.__mro__) for n in c.__dict__.get("deviations", ()))),
        "__module__": __name__,
        "__qualname__": name.replace("_", ""),
    }
    if spec.two_hands is not None:
        attrs |= {"bimanual": True, "default_embodiment": "bimanual_floating_shadow",
                  "deviations": (*attrs["deviations"], TWO_HANDS + spec.two_hands)}
    return register(type(attrs["__qualname__"], (GeneratedMultiGoal,), attrs))


VARIANTS: dict[str, type[MultiGoalTask]] = {
    f"{p}_{a}": make_variant(p, a) for p in PRIMARIES for a in ADDONS if a != p}
globals().update({cls.__qualname__: cls for cls in VARIANTS.values()})
