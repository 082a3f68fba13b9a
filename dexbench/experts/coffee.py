"""MakeCoffee: pour the milk, put the mug in front of the machine's spout, press the lever.

The carton (0.3 kg) slips out of a hand that holds it upright and then turns it, so it is
tipped over first: the hanging finger pads push its upper face away from the mug and it
falls onto its side. Lying, it is grasped from above with the fingers along it, hooking
over its top end, and lifted (it sags to about 65-75 deg; the hand pitches down to keep it
near level) with its spout over the mug's rim: that is the task's pour (tilt >= 70 deg).
It is then led away from the mug and dropped. The mug is carried by its body to the front
of the drip tray and let go once the placement has latched; the hand backs out from under
the machine's head, rises above it, moves over the lever's outer side and presses the
lever down with its finger tips.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import torch

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.adapter import (
    ActionAdapter,
    HandCommand,
    palm_and_finger_sites,
    tips_in_palm_frame,
)
from dexbench.experts.base import host_ids
from dexbench.experts.grasp import GraspExpert, GraspPlan, Phase
from dexbench.experts.motion import palm_down, pitch_down, step_towards
from dexbench.experts.press import PressExpert, PressPlan
from dexbench.experts.sequence import SequenceExpert
from dexbench.tasks.predicates import tilt_deg

SPOUT = (0.03, 0.0, 0.16)  # `add_milk_carton`'s spout point, carton frame (tested equal)
CARTON_HALF = 0.03  # m, its half width
TIP_AWAY = (0.0, 1.0, 0.0)  # world direction the carton is tipped over in (away from the mug)
TIP_HEIGHT = 0.12  # m above the table the finger tips push the carton's face (it is 0.14)
TIP_START = 0.04  # m short of the carton's face the finger tips start
TIP_PUSH = 0.1  # m the finger tips push on past the face
TIPPED = 60.0  # deg: the carton is falling over, the push is done
POUR_ABOVE = 0.1  # m the spout is held above the rim
POUR_HIGH = 0.1  # m higher while it is still more than 2 * `POUR_NEAR` away
POUR_NEAR = 0.03  # m
PARK_AWAY = 0.1  # m the poured carton's spout is led on, away from the mug
PARK_CLEAR = 0.2  # m between carton and mug (their origins) where the carton is let go
TRAY_FRONT = 0.05  # m the mug stands in front of the cup spot (task allows 0.09)
TRAY_DROP = 0.015  # m above the drip tray the mug is let go
BACK_OFF = 0.12  # m the hand backs away from the machine's front after placing the mug
CLEAR_ABOVE = 0.15  # m above the machine's top the hand rises before going to the lever
MACHINE_TOP = 0.34  # m, `add_coffee_machine`'s head and tower top above its base
LEVER_OUT = 0.15  # m outside the machine's side the hand waits above the lever
REACH_SPEED = 0.3  # m/s of the open hand moving on its own
ARRIVED = 0.01  # m
TURN_RATE = 2.0  # rad/s
LEVEL_TILT = 85.0  # deg the held carton is kept tipped while pouring
LEVEL_RATE = 0.5  # rad/s
LEVEL_MAX = 0.8  # rad


def _stage(env: DexEnv) -> np.ndarray:
    return env.task.completed(env.view).cpu().numpy()


def _tilt(env: DexEnv) -> np.ndarray:
    return tilt_deg(env.view.axis("milk", (0.0, 0.0, 1.0))).cpu().numpy()


def _carton_up(env: DexEnv) -> np.ndarray:
    return env.view.axis("milk", (0.0, 0.0, 1.0)).cpu().numpy()


def _carton_target(env: DexEnv) -> np.ndarray:
    """Where the spout goes: over the rim; once poured, straight away from the mug."""
    view = env.view
    rim = view.point_pos(*env.task.objects["mug"].points["rim"]).cpu().numpy()
    spout = view.point_pos("milk", SPOUT).cpu().numpy()
    # Come in high: the carton hangs below the spout; go down only once over the rim.
    off = np.linalg.norm((spout - rim)[:, :2], axis=1)
    above = POUR_ABOVE + POUR_HIGH * np.clip((off - POUR_NEAR) / POUR_NEAR, 0.0, 1.0)
    pour = rim + above[:, None] * [0.0, 0.0, 1.0]
    return np.where((_stage(env) == 0)[:, None], pour, spout + PARK_AWAY * _from_mug(env))


def _from_mug(env: DexEnv) -> np.ndarray:
    """(N, 3) horizontal unit vectors from the mug to the carton."""
    view = env.view
    away = (view.body_pos("milk") - view.body_pos("mug")).cpu().numpy()
    away[:, 2] = 0.0
    return away / np.maximum(np.linalg.norm(away, axis=1, keepdims=True), 1e-9)


def _carton_parked(env: DexEnv) -> np.ndarray:
    """Poured and carried well clear of the mug: let go (it drops onto the table)."""
    view = env.view
    apart = (view.body_pos("milk") - view.body_pos("mug"))[:, :2].norm(dim=1).cpu().numpy()
    return (_stage(env) >= 1) & (apart > PARK_CLEAR)


def _along_carton(env: DexEnv) -> np.ndarray:
    """Grasp yaw with the fingers towards the lying carton's top (its spout end)."""
    up = _carton_up(env)
    return np.arctan2(up[:, 1], up[:, 0])


def _tip_point(env: DexEnv, lead: float) -> np.ndarray:
    """Finger tips `lead` m past the carton's near face, high on it (`TIP_AWAY` is ahead)."""
    home = env.view.initial_body_pos["milk"].cpu().numpy()
    return home + (lead - CARTON_HALF) * np.asarray(TIP_AWAY) + [0.0, 0.0, TIP_HEIGHT]


class ReachExpert:
    """Move the open hand straight to `target(env, start)` (N, 3), `start` being where the
    palm was at the hand-over. Without `yaw` the palm goes there keeping its orientation;
    with it, the hand turns palm-down, fingers along `yaw` (rad) tilted down by `pitch`,
    and its finger tips (their mean, thumb left out) go there."""

    def __init__(self, env: DexEnv, target: Callable[[DexEnv, np.ndarray], np.ndarray],
                 yaw: float | None = None, pitch: float = 0.0, side: str = "right") -> None:
        self.env, self.target, self.yaw, self.pitch, self.side = env, target, yaw, pitch, side
        self.adapter = ActionAdapter(env)
        self._palm, self._tips = palm_and_finger_sites(env, side)
        n = env.num_envs
        self.pos, self.start = np.zeros((n, 3)), np.zeros((n, 3))
        self.rot = np.repeat(np.eye(3)[None], n, axis=0)
        self.tips = np.zeros((n, 3))  # finger tips in the hand frame

    def reset(self, env_ids: torch.Tensor) -> None:
        ids = host_ids(env_ids)
        pos, rot, tips = tips_in_palm_frame(self.env, self._palm, self._tips)
        self.pos[ids], self.rot[ids] = pos[ids], rot[ids]
        self.tips[ids] = tips[ids].mean(axis=1)
        self.start[ids] = self.pos[ids]
        self.adapter.reset(ids)

    def _goal(self) -> tuple[np.ndarray, np.ndarray]:
        if self.yaw is None:
            return self.target(self.env, self.start), self.rot
        rot = palm_down(np.full(self.env.num_envs, self.yaw)) @ pitch_down(self.pitch)
        return self.target(self.env, self.start) - np.einsum("nij,nj->ni", rot, self.tips), rot

    def arrived(self) -> np.ndarray:
        return np.linalg.norm(self.pos - self._goal()[0], axis=1) < ARRIVED

    def act(self) -> torch.Tensor:
        pos, rot = self._goal()
        self.pos, self.rot = step_towards(self.pos, self.rot, pos, rot,
                                          REACH_SPEED * self.env.control_dt,
                                          TURN_RATE * self.env.control_dt)
        command = HandCommand(self.pos, self.rot, np.zeros(self.env.num_envs))
        return self.adapter.actions({self.side: command})


class LevelPourExpert(GraspExpert):
    """The carton's grasp, whose carry also tips the hand fingers-down (up to
    `LEVEL_MAX`) as far as keeps the held carton level until the pour has latched: held
    by one end, it sags by 20-30 deg."""

    def __init__(self, env: DexEnv, plan: GraspPlan, side: str = "right") -> None:
        super().__init__(env, plan, side)
        self.angle = np.zeros(env.num_envs)
        self.base = self.grasp_rot.copy()

    def act(self) -> torch.Tensor:
        carry = self.phase == Phase.CARRY
        start = carry & (self.angle == 0.0)
        self.base[start] = self.grasp_rot[start]
        sag = np.where(_stage(self.env) == 0, LEVEL_TILT - _tilt(self.env), 0.0)
        step = LEVEL_RATE * self._dt * np.clip(sag / 10.0, -1.0, 1.0)
        self.angle = np.where(carry, np.clip(self.angle + step, 0.0, LEVEL_MAX), 0.0)
        for i in np.flatnonzero(carry):
            self.grasp_rot[i] = self.base[i] @ pitch_down(self.angle[i])
        return super().act()


def _in_front_of_spout(env: DexEnv) -> np.ndarray:
    """Where the mug goes: on the drip tray's front, a little above it."""
    view = env.view
    spot = view.point_pos(*env.task.objects["machine"].points["cup_spot"])
    front = view.axis("machine", (1.0, 0.0, 0.0))
    return (spot + TRAY_FRONT * front).cpu().numpy() + [0.0, 0.0, TRAY_DROP]


def _clear_height(env: DexEnv) -> np.ndarray:
    return env.view.body_pos("machine")[:, 2].cpu().numpy() + MACHINE_TOP + CLEAR_ABOVE


def _backed_off(env: DexEnv, start: np.ndarray) -> np.ndarray:
    """In front of where the hand let go of the mug: out from under the machine's head."""
    return start + BACK_OFF * env.view.axis("machine", (1.0, 0.0, 0.0)).cpu().numpy()


def _straight_up(env: DexEnv, start: np.ndarray) -> np.ndarray:
    """Above where the hand let go of the mug, clear of the machine's top."""
    return np.column_stack([start[:, :2], _clear_height(env)])


def _beside_lever(env: DexEnv, start: np.ndarray) -> np.ndarray:
    """High up, outside the machine's lever side: the press then comes down from there."""
    view = env.view
    side = view.axis("machine", (0.0, 1.0, 0.0)).cpu().numpy()
    tip = view.point_pos("machine/lever", LEVER.point).cpu().numpy()
    return np.column_stack([(tip + LEVER_OUT * side)[:, :2], _clear_height(env)])


# The tipped-over carton, fingers along it towards its top, hooking over the top's end
# face: lifted, it hangs at 65-75 deg with its spout leading.
CARTON = GraspPlan("milk", point=(0.0, 0.0, 0.095), shift=(0.0, 0.0, -0.03), pitch=0.3,
                   yaw="none", yaw_offset=_along_carton, target=_carton_target,
                   goal_point=SPOUT, let_go=_carton_parked)
# Let go as soon as the placement has latched: the task counts the mug within 9 cm of the
# spot, and the hand then stays clear of the machine's head.
MUG = GraspPlan("mug", point=(0.0, 0.0, 0.05), yaw="none", target=_in_front_of_spout,
                release=True, let_go=lambda e: _stage(e) >= 2)
# Finger tips tilted down onto the lever near its tip, from just outside it, the fingers
# pointing at the machine's side: the hand stays outside the machine.
LEVER = PressPlan("machine/lever", (0.07, 0.03, 0.0), yaw=-math.pi / 2, pitch=0.4)


def make_coffee(env: DexEnv) -> SequenceExpert:
    """Tip the carton over, pour, place the mug, back off and rise clear of the machine,
    press the lever."""
    # Fingers hanging, pads towards the push: the hand stays above the carton's top.
    tip = {"yaw": math.atan2(TIP_AWAY[1], TIP_AWAY[0]), "pitch": math.pi / 2}
    above = ReachExpert(env, lambda e, _: _tip_point(e, -TIP_START) + [0.0, 0.0, 0.1], **tip)
    down = ReachExpert(env, lambda e, _: _tip_point(e, -TIP_START), **tip)
    push = ReachExpert(env, lambda e, _: _tip_point(e, TIP_PUSH), **tip)
    carton, mug = LevelPourExpert(env, CARTON), GraspExpert(env, MUG)
    back, rise = ReachExpert(env, _backed_off), ReachExpert(env, _straight_up)
    over = ReachExpert(env, _beside_lever)
    return SequenceExpert(env, [
        (above, lambda e: torch.as_tensor(above.arrived())),
        (down, lambda e: torch.as_tensor(down.arrived())),
        (push, lambda e: torch.as_tensor(push.arrived() | (_tilt(e) > TIPPED))),
        (carton, lambda e: torch.as_tensor(carton.phase == Phase.DONE)),
        (mug, lambda e: torch.as_tensor(mug.phase == Phase.DONE)),
        (back, lambda e: torch.as_tensor(back.arrived())),
        (rise, lambda e: torch.as_tensor(rise.arrived())),
        (over, lambda e: torch.as_tensor(over.arrived())),
        (PressExpert(env, LEVER), lambda e: e.task.success(e.view))])
