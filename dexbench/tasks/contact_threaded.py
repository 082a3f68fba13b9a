"""Contact-rich threading: start a nut on a fixed bolt and turn it down the thread."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import torch

from dexbench.assets import fasteners
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, InsertPlan, SequencePlan, Step, TwistPlan
from dexbench.tasks.templates import Placement, TabletopTask

NUT_RAISED = 0.03  # m: the held nut is clear of the table
NUT_DROPPED = 0.015  # m: back on the table, it is grasped again
KEY_HEIGHT = 0.012  # m: the thread's key (`fasteners.add_threaded_bolt`)
ON_KEY = 0.003  # m: the nut's bottom this near the key's top rests on it ...
ROUND_BOLT = 0.006  # m: ... centred this near the bolt's axis (tilted a little)


# Grasped from above and lifted; lowered over the bolt, turned about it until its hex
# bore lines up with the thread's key, pushed down; once on the key (or resting on its
# top, flats crossed) let go, grasped again and turned a stroke at a time, as fingers run
# a nut down a bolt (a nut resting on the key drops onto it as it turns into line).
NUT_PLAN = SequencePlan((
    Step(GraspPlan("nut", yaw="none", lift=0.1, settle=0.5),
         until=lambda e, grasp: grasp.carrying & (
             e.task.lift(e.view, "nut").cpu().numpy() > NUT_RAISED)),
    Step(InsertPlan("nut", "bolt", head="bottom", shaft="down", target="start",
                    key=("key", "key", math.pi / 3)),
         until=lambda e, insert: e.task.on_key(e.view).cpu().numpy()),
    Step(TwistPlan("nut", "centre", stroke=-2.4, yaw=1.2, turn_rate=4.0))),
    # Dropped, or lining up too long (not once it is on the thread: turning it is slow).
    restart=lambda e, experts: ((e.task.lift(e.view, "nut") < NUT_DROPPED).cpu().numpy()
                                | (experts[1].stalled & ~e.task.on_key(e.view).cpu().numpy())))


@register
class NutThread(TabletopTask):
    """A hex nut threaded onto a fixed bolt.

    MuJoCo has no screw joint, so the thread is a mechanism inside the bolt
    (`dexbench.assets.fasteners`): a hidden follower, a short hex key on a flange, slides
    and turns about the bolt's axis with its descent tied to its turn by a joint
    equality (8 mm per turn) for the whole episode. The nut's hex bore fits over the key
    only with their flats lined up; it then rests on the flange, and turning the nut
    turns the key by contact, which lets both down the bolt. The follower collides with
    the nut alone (it stands for the thread flanks between nut and bolt) and its friction
    loss makes the thread self-locking, so the nut gets down only by being turned.
    Nothing switches on when the nut arrives: the mechanism is the same from the first
    step to the last.
    """

    name = "NutThread"
    category = "contact_rich"
    instruction = "Screw the nut onto the bolt."
    description = ("Align a nut with a fixed bolt and thread it down onto the bolt. The "
                   "thread is a hidden follower on the bolt whose turn and descent are tied "
                   "by a joint equality (8 mm per turn) all episode; the nut's hex bore "
                   "engages its hex key only by contact, flats lined up, and rests on its "
                   "flange, so the nut goes down only as it is turned.")
    success_text = ("The nut is centred within 0.0025 m of the bolt axis and its bottom is "
                    "within 0.002 m of the threaded-down depth, 1.5 turns (12 mm) down the "
                    "bolt, on its shoulder.")
    deviations = ("The paper gives no reset ranges, pitch or sizes: ours (an 8 mm pitch, "
                  "toy-construction thread on a 19 mm bolt; a 50 mm nut, 40 mm tall).",
                  "The thread holds the nut down only by friction: lifted off, it comes off; "
                  "its friction is a constant 0.02 N m, so a press harder than about 15 N "
                  "spins the nut down the coarse thread (turning it, as the equality ties).")
    placements: ClassVar = {
        "bolt": Placement((0.05, 0.15), (-0.15, 0.15), clearance=0.05),
        "nut": Placement((-0.15, -0.05), (-0.20, 0.20)),
    }
    reset_joints: ClassVar = {"bolt/advance": "upper", "bolt/thread": "upper"}
    contact_objects = ("nut",)
    centred, depth_tolerance = 0.0025, 0.002
    expert = NUT_PLAN

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"bolt": fasteners.add_threaded_bolt(spec, "bolt"),
                "nut": fasteners.add_nut(spec, "nut")}

    def _offsets(self, view: SceneView, point: str) -> tuple[torch.Tensor, torch.Tensor]:
        """Signed height of the nut's bottom above the bolt's `point` along its axis, and
        the nut centre's distance from the axis."""
        axis = view.axis(*self.objects["bolt"].axes["bore"])
        base = self.point(view, "bolt", point)
        along = ((self.point(view, "nut", "bottom") - base) * axis).sum(dim=1)
        rel = self.point(view, "nut", "centre") - base
        lateral = (rel - (rel * axis).sum(dim=1, keepdim=True) * axis).norm(dim=1)
        return along, lateral

    def on_key(self, view: SceneView) -> torch.Tensor:
        """(N,) the nut is over the bolt's tip, down to the thread's key or round it (the
        expert's cue to turn it: turned, a nut resting on the key drops onto it)."""
        along, lateral = self._offsets(view, "start")
        return (along < KEY_HEIGHT + ON_KEY) & (lateral < ROUND_BOLT)

    def success(self, view: SceneView) -> torch.Tensor:
        along, lateral = self._offsets(view, "seated")
        return (along.abs() <= self.depth_tolerance) & (lateral <= self.centred)

    def progress(self, view: SceneView) -> torch.Tensor:
        along, lateral = self._offsets(view, "seated")
        return (1.0 - (along.abs() + lateral) / 0.5).clamp(min=0.0)
