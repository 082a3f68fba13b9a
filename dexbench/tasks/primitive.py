"""Primitive skills: grasp, lift, place, press, turn (paper appendix, "Primitive")."""

from __future__ import annotations

import math
from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import articulated, objects, procedural
from dexbench.assets.objects import ObjectInfo, add_free_box
from dexbench.envs.arena import BACKDROP_HALF_SIZE
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, PressPlan, StackItem, StackLiftPlan, TurnPlan, task_goal
from dexbench.tasks.predicates import dist, xy_dist
from dexbench.tasks.templates import (
    SPEED_NOTE,
    ArticulatedTask,
    LiftTask,
    Placement,
    TabletopTask,
    uniform_points,
)

CENTRE = Placement(x=(-0.10, 0.10), y=(-0.15, 0.15))


@register
class PickCube(LiftTask):
    name = "PickCube"
    category = "primitive"
    instruction = "Pick up the cube and lift it above the table."
    description = "Grasp a cube on the tabletop and lift it away from the surface."
    success_text = "The cube is lifted at least 0.20 m above its resetting height."
    placements: ClassVar = {"cube": CENTRE}
    lifted, lift_threshold = "cube", 0.20
    expert = GraspPlan("cube")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cube": add_free_box(spec, "cube", [0.025] * 3, 0.1)}


def _on_base_cube(env: DexEnv) -> np.ndarray:
    """Where the carried cube's centre goes: 2 mm above resting on the base cube."""
    height = 2 * env.task.half + 0.002
    return env.view.body_pos("base_cube").cpu().numpy() + [0.0, 0.0, height]


@register
class StackCube(TabletopTask):
    name = "StackCube"
    category = "primitive"
    instruction = "Stack the red cube on top of the green cube."
    description = "Pick and place one cube on top of another cube to form a stable stack."
    success_text = ("The moving cube is stabilized within 0.035 m horizontally and 0.025 m "
                    "vertically of resting directly on top of the base cube.")
    placements: ClassVar = {"cube": CENTRE, "base_cube": Placement((-0.10, 0.10),
                                                                   (-0.20, 0.20), clearance=0.05)}
    half = 0.025
    xy_tol, z_tol, max_speed = 0.035, 0.025, 0.05
    expert = GraspPlan("cube", target=_on_base_cube, release=True)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cube": add_free_box(spec, "cube", [self.half] * 3, 0.1),
                "base_cube": add_free_box(spec, "base_cube", [self.half] * 3, 0.1,
                                          rgba=(0.2, 0.7, 0.3, 1.0))}

    def _offset(self, view: SceneView) -> torch.Tensor:
        return view.body_pos("cube") - view.body_pos("base_cube")

    def success(self, view: SceneView) -> torch.Tensor:
        off = self._offset(view)
        still = view.free_joint_vel(self.objects["cube"].free_joint)[:, :3].norm(dim=1)
        return ((off[:, :2].norm(dim=1) <= self.xy_tol)
                & ((off[:, 2] - 2 * self.half).abs() <= self.z_tol)
                & (still <= self.max_speed))

    def progress(self, view: SceneView) -> torch.Tensor:
        off = self._offset(view)
        off[:, 2] -= 2 * self.half
        return 1.0 - off.norm(dim=1) / 0.3

    def focus(self, view: SceneView) -> torch.Tensor:
        return view.body_pos("cube")


@register
class RelocateSphere(TabletopTask):
    name = "RelocateSphere"
    category = "primitive"
    instruction = "Move the ball to the target."
    description = ("Move a sphere from its initial tabletop position to the commanded "
                   "target location.")
    success_text = "The sphere comes within 0.03 m of a goal point sampled once per episode."
    placements: ClassVar = {"sphere": CENTRE}
    tolerance = goal_marker = 0.03
    expert = GraspPlan("sphere", shift=(0.025, 0.0, 0.0), yaw="none", target=task_goal)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"sphere": objects.add_sphere(spec, "sphere", radius=0.03, mass=0.1)}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        return uniform_points(rngs, (-0.15, 0.15), (-0.20, 0.20), (0.05, 0.20))

    def success(self, view: SceneView) -> torch.Tensor:
        return dist(view.body_pos("sphere"), view.goal) <= self.tolerance

    def progress(self, view: SceneView) -> torch.Tensor:
        return 1.0 - dist(view.body_pos("sphere"), view.goal) / 0.4


@register
class PickUpStick(LiftTask):
    name = "PickUpStick"
    category = "primitive"
    instruction = "Pick up the stick and keep it upright."
    description = ("Grasp a stick on the tabletop and lift it while maintaining an upright "
                   "orientation.")
    success_text = ("The stick is lifted at least 0.20 m above its reset height and stays "
                    "within 30° of vertical.")
    placements: ClassVar = {"stick": CENTRE}
    lifted, lift_threshold, max_tilt = "stick", 0.20, 30.0
    # Thin and upright: held 3 cm below its top, the palm a little lower than for a cube.
    expert = GraspPlan("stick", point=("top", (0.0, 0.0, -0.032)), shift=(0.01, 0.0, -0.02),
                       yaw="none")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"stick": objects.add_stick(spec, "stick")}


@register
class RelocateObject(TabletopTask):
    name = "RelocateObject"
    category = "primitive"
    instruction = "Move the bottle to the target point above the table."
    description = ("Move a rigid object from the tabletop reset region to a sampled 3D goal "
                   "position above the table.")
    success_text = ("The object is moved to within 0.03 m of a sampled goal point, roughly "
                    "within 0.2 m of table center and 0.15-0.25 m above the table.")
    placements: ClassVar = {"bottle": CENTRE}
    tolerance = goal_marker = 0.03
    # Tall: fingers tilted down so they straddle the shoulder instead of landing on the cap.
    expert = GraspPlan("bottle", point=("top", (0.0, 0.0, -0.06)), shift=(0.01, 0.0, 0.0),
                       yaw="none", pitch=0.6, target=task_goal, goal_point="centre")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"bottle": procedural.add_bottle(spec, "bottle")}

    def sample_goal(self, rngs: list[np.random.Generator]) -> np.ndarray:
        out = []
        for r in rngs:
            radius, angle = 0.2 * math.sqrt(r.uniform()), r.uniform(-math.pi, math.pi)
            out.append([radius * math.cos(angle), radius * math.sin(angle), 0.0])
        pts = np.array(out)
        pts[:, 2] = uniform_points(rngs, (0, 0), (0, 0), (0.15, 0.25))[:, 2]
        return pts

    def _centre(self, view: SceneView) -> torch.Tensor:
        return self.point(view, "bottle", "centre")

    def success(self, view: SceneView) -> torch.Tensor:
        return dist(self._centre(view), view.goal) <= self.tolerance

    def progress(self, view: SceneView) -> torch.Tensor:
        return 1.0 - dist(self._centre(view), view.goal) / 0.4


@register
class TurnOnSwitch(ArticulatedTask):
    name = "TurnOnSwitch"
    category = "primitive"
    instruction = "Turn on the switch."
    description = "Flip an articulated switch from the off state toward the on state."
    success_text = "The switch moves at least 80% of its reachable travel from its reset position."
    placements: ClassVar = {"switch": Placement((0.0, 0.15), (-0.15, 0.15), (-0.3, 0.3))}
    joint = "switch/rocker"
    # Fingertips, tilted down, on the paddle's "on" end: it rocks over.
    expert = PressPlan("switch", "press", pitch=math.radians(50))

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"switch": articulated.add_switch(spec, "switch")}


@register
class PushButton(ArticulatedTask):
    name = "PushButton"
    category = "primitive"
    instruction = "Press the button."
    description = "Move the fingertip or hand into an articulated button and press it down."
    success_text = "The button is pressed at least 80% of its roughly 0.015 m travel."
    placements: ClassVar = {"button": Placement((-0.05, 0.15), (-0.15, 0.15))}
    joint, reset_at = "button/press", "upper"
    expert = PressPlan("button", "cap", with_fingers=False)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"button": articulated.add_button(spec, "button")}


@register
class OpenFaucet(ArticulatedTask):
    name = "OpenFaucet"
    category = "primitive"
    instruction = "Turn the faucet handle to open the faucet."
    description = ("Turn an articulated faucet handle from its initial pose toward the target "
                   "turned state.")
    success_text = "The handle is turned at least 80° from its reset angle."
    placements: ClassVar = {"faucet": Placement((0.3, 0.5), (-0.2, 0.2), (math.pi - 0.3,
                                                                           math.pi + 0.3))}
    # The hand works at the lever's tip: 8 cm beyond the faucet's centre (which faces the
    # robot, yaw about pi), 18.5 cm above the table (`articulated.add_faucet`).
    workspace = (placements["faucet"].centre[0] + 0.08, placements["faucet"].centre[1], 0.185)
    joint, min_turn = "faucet/handle", math.radians(80.0)
    expert = TurnPlan("faucet", "handle_tip")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"faucet": articulated.add_faucet(spec, "faucet")}


# The standing cylinder is the first choice of base: a pinched cylinder hangs tilted and
# topples off a box or prism, while a box or prism set on the cylinder stays, and the
# tall cylinder gives the side grasp's thumb and index finger the most to hold.
STACK_ITEMS: dict[str, StackItem] = {
    "box": StackItem(yaw="box", base=1, period=np.pi / 2),
    # Lying: 4 cm wide along its x, 9 cm long; pinched across its width, 2 cm off the
    # cube grasp along the hand's y, where it hangs least rolled (about 15 deg, not 30).
    "prism": StackItem(synergy="pinch", shift=(0.03, 0.02, 0.0), yaw="body", base=2,
                  period=np.pi, across=True),
    # Standing: pinched around its middle (only if some other shape became the base).
    "cylinder": StackItem(synergy="pinch", shift=(0.03, 0.0, 0.0), base=0),
    "ball": StackItem(shift=(0.025, 0.0, 0.0)),
    # Lying along its x: held in a power grasp with the fingers along its axis, so it
    # sits level (a pinch left a fingertip below it, which tipped the base over) and
    # slides along its axis rather than rolling as the hand lets go; on the base it
    # lies along the side grasp's fingers, not into the palm, which would push it off.
    "capsule": StackItem(shift=(0.025, 0.0, 0.0), yaw="body", base=3, period=np.pi),
}


# Hand poses that start the side grasp: open fingers, the thumb turned towards the palm
# (opposing the fingers, as in `power`) but not flexed, so it slides in under the base.
SIDE_READY: dict[str, dict[str, float]] = {"shadow": {"A_THJ4": 1.22}}


@register
class GraspTwoItems(TabletopTask):
    """Five candidate shapes exist; each episode two are on the table, three parked
    outside the backdrop's walls, which hide them from every camera."""

    name = "GraspTwoItems"
    category = "primitive"
    instruction = "Pick up both objects on the table at the same time."
    description = ("Randomly select two primitive objects from the candidate set and lift "
                   "both selected objects.")
    success_text = ("Both of the two randomly selected primitive shapes, out of 5 candidates, "
                    "are lifted at least 0.20 m above the tabletop at the same time.")
    candidates = ("box", "ball", "cylinder", "capsule", "prism")
    placements: ClassVar = {n: Placement((-0.15, 0.15), (-0.25, 0.25)) for n in candidates}
    deviations = (SPEED_NOTE,)
    lift_threshold = 0.20
    parking_x = BACKDROP_HALF_SIZE + 0.5  # unselected shapes rest on the floor out there
    contact_objects = candidates
    expert = StackLiftPlan(candidates, STACK_ITEMS, SIDE_READY)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return objects.add_primitive_set(spec, self.candidates)

    def sample_reset(self, rngs: list[np.random.Generator]):
        sample = super().sample_reset(rngs)
        for env, rng in enumerate(rngs):
            chosen = set(rng.choice(len(self.candidates), size=2, replace=False).tolist())
            for k, name in enumerate(self.candidates):
                if k not in chosen:
                    pose = sample.free_poses[self.objects[name].free_joint][env]
                    pose[:3] = [self.parking_x + 0.2 * k, 0.0, self.objects[name].rest_height]
        return sample

    def _lifts(self, view: SceneView) -> torch.Tensor:
        return torch.stack([self.lift(view, n) for n in self.candidates], dim=1)

    def success(self, view: SceneView) -> torch.Tensor:
        slow = torch.stack([self.slow(view, n) for n in self.candidates], dim=1)
        return ((self._lifts(view) >= self.lift_threshold) & slow).sum(dim=1) >= 2

    def progress(self, view: SceneView) -> torch.Tensor:
        top2 = self._lifts(view).topk(2, dim=1).values.clamp(0.0, self.lift_threshold)
        return top2.sum(dim=1) / (2 * self.lift_threshold)

    def focus(self, view: SceneView) -> torch.Tensor:
        pos = torch.stack([view.body_pos(self.objects[n].root) for n in self.candidates], 1)
        near = xy_dist(pos.flatten(0, 1), torch.zeros_like(pos.flatten(0, 1))).view(
            pos.shape[:2]).argmin(dim=1)
        return pos[torch.arange(len(pos), device=pos.device), near]
