"""Bimanual handover: the right hand passes a cube over to the left hand."""

from __future__ import annotations

from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets.objects import ObjectInfo, add_free_box
from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.dex_env import DexEnv
from dexbench.envs.task_api import SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import BothHandsPlan, GraspPlan
from dexbench.tasks.templates import Placement, TabletopTask

GRIP_FORCE = 1.6  # N on one link of the left hand: a firm grip (the paper's)
HALF = 0.025  # m, the cube's half size
# Where the right hand sets the cube down for the left (ours): the middle of the table.
SPOT = np.array([0.0, 0.0, TABLE_TOP_Z + HALF])
SET_DOWN = 0.01  # m: the cube this near its spot, resting and let go, is handed over


def gripping(view: SceneView, obj: str, side: str, force: float = GRIP_FORCE) -> torch.Tensor:
    """(N,) hand `side` presses on `obj` with at least `force` (N) on one of its links."""
    return (view.link_forces(obj, side).norm(dim=-1) >= force).any(dim=1)


def untouched(view: SceneView, obj: str, side: str) -> torch.Tensor:
    """(N,) no link of hand `side` is in active contact with `obj` (no force on any)."""
    return (view.link_forces(obj, side).norm(dim=-1) == 0.0).all(dim=1)


def set_down(env: DexEnv) -> np.ndarray:
    """(N,) the cube rests on its spot and the right hand has let go of it."""
    cube = env.view.body_pos("cube").cpu().numpy()
    return ((np.linalg.norm(cube - SPOT, axis=1) < SET_DOWN)
            & untouched(env.view, "cube", "right").cpu().numpy())


@register
class BimanualHandover(TabletopTask):
    name = "BimanualHandover"
    category = "bimanual"
    instruction = "Hand the cube over from the right hand to the left hand."
    description = ("Transfer a cube so that the left hand holds it while the right hand "
                   "releases it and the object remains stable.")
    success_text = ("The left hand grips firmly the cube with a contact force of at least "
                    "1.6 N on at least one link, while the right hand having no active "
                    "contact with the cube.")
    deviations = ("Not in the paper: the cube must also move slower than 0.5 m/s (it "
                  "remains stable), so a cube falling past the left hand is not held.",)
    episode_seconds = 10.0
    bimanual = True
    default_embodiment = "bimanual_floating_shadow"
    # The paper gives no reset region: ours, on the right hand's side of the table.
    placements: ClassVar = {"cube": Placement((-0.05, 0.10), (-0.25, -0.10))}
    link_force_bodies: ClassVar = ("cube",)
    # The right hand picks the cube up and sets it down in the middle of the table (it
    # lets go 2 mm above the cube's resting height) and backs off 15 cm up, clear of the
    # left hand coming down over the cube; the left hand waits until the cube rests there
    # and the right hand is off it, then picks it up and holds it 10 cm up. Its grasp
    # point is 2.6 cm over along the hand's y axis: the `grasp_offset` (a right hand's)
    # mirrored for the left hand. (Passed in the air instead, the left hand hooking
    # under the cube held from above, 1 of 8 held it: the hook could not press it, and
    # as the right hand let go it fell.)
    expert = BothHandsPlan({
        "right": GraspPlan("cube", release=True, back_off=0.15,
                           target=lambda env: np.repeat(SPOT[None] + [0.0, 0.0, 0.002],
                                                        env.num_envs, 0)),
        "left": GraspPlan("cube", shift=(0.0, 0.026, 0.0), lift=0.1, wait=set_down),
    })

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"cube": add_free_box(spec, "cube", [HALF] * 3, 0.1)}

    def success(self, view: SceneView) -> torch.Tensor:
        return (gripping(view, "cube", "left") & untouched(view, "cube", "right")
                & self.slow(view, "cube"))

    def progress(self, view: SceneView) -> torch.Tensor:
        left = view.link_forces("cube", "left").norm(dim=-1).max(dim=1).values
        grip = (left / GRIP_FORCE).clamp(0.0, 1.0)
        return 0.5 * grip + 0.5 * grip * untouched(view, "cube", "right").to(grip.dtype)
