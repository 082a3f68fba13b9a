"""Scripted, embodiment-agnostic experts: `make_expert(env)` runs the task's own plan.

A task's `expert` (`dexbench.tasks.plans`) is data: one plan kind, or a sequence of
them. This package holds one closed-loop script per kind (`KINDS`), so it grows by
kinds, never by tasks.
"""

from __future__ import annotations

from typing import Any

from dexbench.envs.dex_env import DexEnv
from dexbench.experts.base import Expert
from dexbench.experts.bimanual import TwoHandLiftExpert
from dexbench.experts.both_hands import BothHandsExpert
from dexbench.experts.either_hand import EitherHandExpert
from dexbench.experts.grasp import GraspExpert, LevelGraspExpert
from dexbench.experts.hold_actuate import HoldActuateExpert
from dexbench.experts.insert import InsertExpert
from dexbench.experts.path_push import PathPushExpert
from dexbench.experts.pinch import PinchExpert
from dexbench.experts.pivot import PivotExpert
from dexbench.experts.pour import PourExpert
from dexbench.experts.press import PressExpert
from dexbench.experts.push import PushExpert
from dexbench.experts.reach import ReachExpert
from dexbench.experts.sequence import SequenceExpert
from dexbench.experts.stack import StackLiftExpert
from dexbench.experts.strike import StrikeExpert
from dexbench.experts.swing import SwingExpert
from dexbench.experts.turn import TurnExpert
from dexbench.experts.twist import TwistExpert
from dexbench.tasks import plans

KINDS: dict[type, Any] = {
    plans.GraspPlan: GraspExpert,
    plans.LevelPlan: LevelGraspExpert,
    plans.PressPlan: PressExpert,
    plans.TurnPlan: TurnExpert,
    plans.PushPlan: PushExpert,
    plans.PathPushPlan: PathPushExpert,
    plans.PivotPlan: PivotExpert,
    plans.TwoHandPlan: TwoHandLiftExpert,
    plans.InsertPlan: InsertExpert,
    plans.PourPlan: PourExpert,
    plans.PinchPlan: PinchExpert,
    plans.ReachPlan: ReachExpert,
    plans.StackLiftPlan: StackLiftExpert,
    plans.StrikePlan: StrikeExpert,
    plans.SwingPlan: SwingExpert,
    plans.TwistPlan: TwistExpert,
}


def build_expert(env: DexEnv, plan: Any) -> Expert:
    """The expert running `plan` (any kind, or a `SequencePlan`, `HoldActuatePlan` or
    `BothHandsPlan` of them) on `env`."""
    if isinstance(plan, plans.SequencePlan):
        return SequenceExpert(env, plan, build_expert)
    if isinstance(plan, plans.BothHandsPlan):
        return BothHandsExpert(env, plan, lambda hand, side: KINDS[type(hand)](env, hand, side))
    if isinstance(plan, plans.HoldActuatePlan):
        def hold(kind: Any, side: str) -> Expert:
            return KINDS[type(kind)](env, kind, side)
        if plan.side == plans.EITHER:
            return EitherHandExpert(env, plan, hold)
        return HoldActuateExpert(env, plan, hold)
    try:
        return KINDS[type(plan)](env, plan)
    except KeyError:
        raise ValueError(f"no expert script for plan kind {type(plan).__name__}") from None


def make_expert(env: DexEnv) -> Expert:
    """The expert for `env`'s task, or an error naming the tasks that have one."""
    plan = getattr(env.task, "expert", None)
    if plan is None:
        from dexbench.tasks.registry import TASKS  # only for the message

        have = sorted(n for n, cls in TASKS.items() if getattr(cls, "expert", None))
        raise ValueError(f"no expert for task {env.task.name!r} yet; experts exist for "
                         f"{', '.join(have)}")
    return build_expert(env, plan)


__all__ = ["Expert", "build_expert", "make_expert"]
