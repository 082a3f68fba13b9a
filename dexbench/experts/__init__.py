"""Scripted, embodiment-agnostic experts: `make_expert(env)` picks the task's script."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import torch

from dexbench.assets.objects import T_SHAPE_RECTS, T_THICKNESS
from dexbench.envs.dex_env import DexEnv
from dexbench.experts.base import Expert
from dexbench.experts.bimanual import TwoHandLiftExpert, TwoHandPlan
from dexbench.experts.coffee import make_coffee
from dexbench.experts.grasp import GraspExpert, GraspPlan, Phase, task_goal
from dexbench.experts.insert import InsertExpert, InsertPlan
from dexbench.experts.motion import body_yaw, turnable_offset
from dexbench.experts.pour import pour_mug
from dexbench.experts.press import PressExpert, PressPlan
from dexbench.experts.push import PushExpert, PushPlan
from dexbench.experts.sequence import SequenceExpert
from dexbench.experts.turn import TurnExpert, TurnPlan
from dexbench.experts.two_items import TwoItemsExpert


def _on_base_cube(env: DexEnv):
    """Where the carried cube's centre goes: just above resting on the base cube."""
    return env.view.body_pos("base_cube").cpu().numpy() + [0.0, 0.0, STACK_HEIGHT]


STACK_HEIGHT = 0.052  # m: two 2.5 cm half-sizes plus a 2 mm drop


def _drawer_pulled(env: DexEnv):
    """A point ahead of the handle along the drawer's opening direction: keep pulling."""
    view = env.view
    handle = view.point_pos("cabinet/drawer", DRAWER_HANDLE)
    return (handle + PULL_LEAD * view.axis("cabinet/drawer", (1.0, 0.0, 0.0))).cpu().numpy()


DRAWER_HANDLE = (0.21, 0.0, 0.0)
PULL_LEAD = 0.1

PLANS: dict[str, GraspPlan] = {
    "PickCube": GraspPlan("cube"),
    "StackCube": GraspPlan("cube", target=_on_base_cube, release=True),
    "RelocateSphere": GraspPlan("sphere", shift=(0.025, 0.0, 0.0), yaw="none",
                                target=task_goal),
    # Thin and upright: held near its top, the palm a little lower than for a cube.
    "PickUpStick": GraspPlan("stick", point=(0.0, 0.0, 0.13), shift=(0.01, 0.0, -0.02),
                             yaw="none"),
    # Tall: fingers tilted down so they straddle the shoulder instead of landing on the cap.
    "RelocateObject": GraspPlan("bottle", point=(0.0, 0.0, 0.12), shift=(0.01, 0.0, 0.0),
                                yaw="none", pitch=0.6,
                                target=task_goal, goal_point=(0.0, 0.0, 0.09)),
    # Hand hanging in front of the handle, palm towards the cabinet: the fingers curl
    # behind the bar and the hand pulls along the drawer's axis.
    "OpenDrawer": GraspPlan("cabinet/drawer", point=DRAWER_HANDLE, yaw="body",
                            pitch=math.pi / 2, target=_drawer_pulled, goal_point=DRAWER_HANDLE,
                            carry_high=False),
}

PRESSES: dict[str, PressPlan] = {
    "PushButton": PressPlan("button/cap", (0.0, 0.0, 0.02), with_fingers=False),
    # Fingertips, tilted down, on the paddle's "on" end: it rocks over.
    "TurnOnSwitch": PressPlan("switch/rocker", (0.03, 0.0, 0.006), pitch=math.radians(50)),
}

TURNS: dict[str, TurnPlan] = {
    "OpenFaucet": TurnPlan("faucet/handle", (-0.08, 0.0, 0.015), "faucet/handle"),
    # Fingers tilted down slide under the raised front edge of the lid, from the front,
    # and lift it up and over; the base's own weight holds it down.
    "OpenLaptop": TurnPlan("laptop/lid", (-0.22, 0.0, 0.0), "laptop/hinge", direction=-1.0,
                           pitch=0.6, yaw_body="laptop", approach=(-1.0, 0.0, 0.3)),
}


def _drawer_then_ball(env: DexEnv) -> Expert:
    """Open the drawer all the way and let go (it stays open), then lift the ball."""
    ball = GraspPlan("sphere", shift=PLANS["RelocateSphere"].shift, yaw="none")
    opened = dataclasses.replace(PLANS["OpenDrawer"], let_go=lambda e: (
        e.task.primary.progress(e.view) >= DRAWER_OPEN / e.task.primary.threshold).cpu().numpy())
    drawer = GraspExpert(env, opened)
    return SequenceExpert(env, [
        (drawer, lambda e: torch.as_tensor(drawer.phase == Phase.DONE)),
        (GraspExpert(env, ball), lambda e: e.task.success(e.view))])


DRAWER_OPEN = 0.95  # of its travel: well past the task's threshold before letting go


def _hole_yaw(env: DexEnv):
    return body_yaw(env.view.body_quat("hole").cpu().numpy())


# Across the shaft, near the grip end: the hand's width leaves the head free to go in.
PEG_GRASP = GraspPlan("peg", point=(-0.035, 0.0, 0.0), shift=(0.0, 0.0, -0.005), yaw="body",
                      yaw_offset=turnable_offset("peg", _hole_yaw, (math.pi / 2, -math.pi / 2)),
                      lift=0.1, settle=0.5)


def _grasp_then_insert(env: DexEnv) -> Expert:
    """Hold the peg across its shaft by the grip end, lift it, then insert it."""
    peg, hole = env.task.objects["peg"], env.task.objects["hole"]
    insert = InsertPlan("peg", peg.points["head"][1], peg.axes["shaft"][1], "hole",
                        hole.points["entrance"][1], hole.points["target"][1],
                        hole.axes["bore"][1])
    grasp, inserter = GraspExpert(env, PEG_GRASP), InsertExpert(env, insert)
    return SequenceExpert(env, [
        (grasp, lambda e: torch.as_tensor((grasp.phase == Phase.CARRY) & (
            e.task.lift(e.view, "peg").cpu().numpy() > PEG_RAISED))),
        (inserter, lambda e: e.task.success(e.view))],
        restart=lambda e: (e.task.lift(e.view, "peg") < PEG_DROPPED) | torch.as_tensor(
            inserter.stalled))


PEG_RAISED = 0.03  # m: the held peg is clear of the table, the hand may turn it
PEG_DROPPED = 0.015  # m: back on the table (or stalled lining up), it is grasped again
# Task-specific scripts, by task: factories of an expert for an env.
SEQUENCES = {
    "OpenDrawer_RelocateSphere": _drawer_then_ball,
    "InsertPeg": _grasp_then_insert,
    "FunctionalPourMug": pour_mug,  # side grasp of the body, turned about the palm normal
    "GraspTwoItems": TwoItemsExpert,  # stack one item on the other, lift both
    "MakeCoffee": make_coffee,  # tip the carton over, pour, place the mug, press the lever
}


def _goal_pose(env: DexEnv) -> np.ndarray:
    """The sampled planar goal (x, y, yaw) of the pushed block's frame."""
    return env.view.goal[:, :3].cpu().numpy()


PUSHES: dict[str, PushPlan] = {
    # Stop pushing (lift off and wait) well inside the 90% overlap success needs.
    "PushT": PushPlan("tee", T_SHAPE_RECTS, 2 * T_THICKNESS, _goal_pose,
                      lambda e: (e.task.overlap(e.view) >= PUSH_DONE_OVERLAP).cpu().numpy()),
}
PUSH_DONE_OVERLAP = 0.95


TWO_HANDS: dict[str, TwoHandPlan] = {
    # Each hand hooks one short rim wall, fingers along the tray's long axis. Centred
    # between the fingers, the tray hangs ~5 deg low on the thumb side; with its centre
    # line 3 cm towards the little finger (hand frame y = +0.03) it hangs level.
    "BimanualLiftTray": TwoHandPlan("tray", {"right": "grip_xneg", "left": "grip_xpos"},
                                    shift=(0.0, 0.043, 0.0)),
}


def make_expert(env: DexEnv) -> Expert:
    """The expert for `env`'s task, or an error naming the tasks that have one."""
    name = env.task.name
    if name in SEQUENCES:
        return SEQUENCES[name](env)
    if name in PLANS:
        return GraspExpert(env, PLANS[name])
    if name in PRESSES:
        return PressExpert(env, PRESSES[name])
    if name in TURNS:
        return TurnExpert(env, TURNS[name])
    if name in PUSHES:
        return PushExpert(env, PUSHES[name])
    if name in TWO_HANDS:
        return TwoHandLiftExpert(env, TWO_HANDS[name])
    raise ValueError(f"no expert for task {name!r} yet; experts exist for "
                     f"{', '.join(sorted({*PLANS, *PRESSES, *TURNS, *SEQUENCES, *PUSHES,
                                          *TWO_HANDS}))}")


__all__ = ["Expert", "make_expert"]
