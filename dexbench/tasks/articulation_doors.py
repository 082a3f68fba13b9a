"""Doors: a latched door whose lever must be turned before it opens (`SwingPlan` with a
latch), and a double-door cupboard opened with both hands together (`BothHandsPlan` of
two `SwingPlan`s)."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import mujoco
import torch

from dexbench.assets import doors
from dexbench.assets.objects import ObjectInfo
from dexbench.envs.task_api import SceneView
from dexbench.tasks.articulation_hinged import FACING_ROBOT, hook_and_swing
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import BothHandsPlan, SwingPlan
from dexbench.tasks.templates import ArticulatedTask, Placement, TabletopTask


def hook_and_swing_at(obj: str, point: str, joint: str) -> SwingPlan:
    """`hook_and_swing` on handle point `point` (one of several handles)."""
    plan = hook_and_swing(obj, joint)
    return dataclasses.replace(plan, grasp=dataclasses.replace(plan.grasp, point=point))


@register
class OpenDoor(ArticulatedTask):
    name = "OpenDoor"
    category = "articulation"
    instruction = "Turn the door's handle and pull the door open."
    description = ("Grasp the handle, then rotate to unblock the door. Then pull the "
                   "articulated door until it reaches the open state.")
    success_text = "The door hinge reaches at least 80% of its full swing range."
    # The frame's front (its root) as near as OpenCabinet's door front.
    placements: ClassVar = {"door": Placement((0.0, 0.15), (-0.15, 0.15), FACING_ROBOT)}
    joint = "door/door"
    reset_joints: ClassVar = {"door/lever": "lower"}
    focus_point = ("door", "handle")
    # The cam clears the strike post from ~38 deg of the lever's 60: turned to 48 deg, it
    # clears it by 10 mm (an arm's wrist may not turn the lever to its stop).
    expert = dataclasses.replace(hook_and_swing("door", joint), latch="door/lever",
                                 latch_turn=0.8)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"door": doors.add_latched_door(spec, "door")}


@register
class OpenDoubleDoor(TabletopTask):
    """Both doors past `threshold` of their swing now, and the control steps at which
    each went past it and has stayed past since at most `max_gap` s apart (steps times
    the env's control period). The step count and those two steps live in
    `SceneView.memory` (simulator state, as a `StageTask`'s progress), so a restored
    state replays exactly."""

    name = "OpenDoubleDoor"
    category = "articulation"
    instruction = "Open both cabinet doors together."
    description = "Open both target cabinet doors in a coordinated manner."
    success_text = ("Both doors reach at least 80% of their full swing range at the same "
                    "time, and the gap between when each door first stays past that point "
                    "is no more than 1.0s.")
    episode_seconds = 8.0
    bimanual = True
    default_embodiment = "bimanual_floating_shadow"
    placements: ClassVar = {"cabinet": Placement((0.15, 0.30), (-0.10, 0.10), FACING_ROBOT)}
    doors: ClassVar = ("cabinet/a/door", "cabinet/b/door")  # the robot's left, right
    reset_joints: ClassVar = dict.fromkeys(doors, "lower")
    threshold: ClassVar[float] = 0.8
    max_gap: ClassVar[float] = 1.0  # s
    memory_size = 3  # steps so far; per door, the step it went past (0: not past now)
    # Each hand hooks the handle of the door on its side and swings it open.
    expert = BothHandsPlan({"left": hook_and_swing_at("cabinet", "handle_a", doors[0]),
                            "right": hook_and_swing_at("cabinet", "handle_b", doors[1])})

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cabinet": doors.add_double_door_cabinet(spec, "cabinet")}

    def _each(self, view: SceneView) -> torch.Tensor:
        """(N, 2) each door's progress over the threshold."""
        return torch.stack([self.joint_progress(view, j) for j in self.doors], dim=1) / \
            self.threshold

    def update(self, view: SceneView) -> None:
        memory = view.memory
        memory[:, 0] += 1
        past = self._each(view) >= 1.0
        since = torch.where(memory[:, 1:] > 0, memory[:, 1:], memory[:, :1])
        memory[:, 1:] = torch.where(past, since, torch.zeros_like(since))

    def _gap(self, view: SceneView) -> torch.Tensor:
        """(N,) seconds between the two doors' going past (inf while one is not)."""
        since = view.memory[:, 1:]
        gap = (since[:, 0] - since[:, 1]).abs() * view.control_dt
        return torch.where((since > 0).all(dim=1), gap, torch.full_like(gap, torch.inf))

    def success(self, view: SceneView) -> torch.Tensor:
        return (self._each(view) >= 1.0).all(dim=1) & (self._gap(view) <= self.max_gap + 1e-9)

    def progress(self, view: SceneView) -> torch.Tensor:
        return self._each(view).clamp(max=1.0).mean(dim=1)

    def focus(self, view: SceneView) -> torch.Tensor:
        """Between the two handles."""
        return 0.5 * (self.point(view, "cabinet", "handle_a")
                      + self.point(view, "cabinet", "handle_b"))

    def state_obs(self, view: SceneView) -> torch.Tensor:
        """Also, per door, the seconds it has stayed past the threshold (0: not past)."""
        memory = view.memory
        held = torch.where(memory[:, 1:] > 0, memory[:, :1] - memory[:, 1:] + 1,
                           torch.zeros_like(memory[:, 1:])) * view.control_dt
        return torch.cat([super().state_obs(view), held.to(view.body_pos(
            self.objects["cabinet"].root).dtype)], dim=1)
