"""Contact-rich picking: a target out of a cluttered corral, a thin plate out of a slot."""

from __future__ import annotations

from typing import ClassVar

import mujoco
import numpy as np
import torch

from dexbench.assets import lab
from dexbench.assets.objects import ObjectInfo
from dexbench.embodiments.builder import TABLE_TOP_Z
from dexbench.envs.task_api import ResetSample, SceneView
from dexbench.tasks.catalog import register
from dexbench.tasks.plans import GraspPlan, PinchPlan, task_goal
from dexbench.tasks.templates import LiftTask, Placement, TabletopTask

CORRAL_CENTRE, CORRAL_HALF = (0.0, 0.0), 0.19
DISTRACTORS = tuple(f"distractor{k}" for k in range(19))
# Object centres stay 3.6 cm inside the fence: the target cube's footprint radius (3.5 cm,
# its half diagonal), the largest, never starts inside the fence.
_INSIDE = tuple((c - CORRAL_HALF + 0.036, c + CORRAL_HALF - 0.036) for c in CORRAL_CENTRE)
# The target's centre stays 7 cm inside (ours): closing round a cube pressed into the
# fence, the fingers land on the fence's top.
_TARGET = tuple((c - CORRAL_HALF + 0.07, c + CORRAL_HALF - 0.07) for c in CORRAL_CENTRE)


@register
class PickFromClutter(LiftTask):
    name = "PickFromClutter"
    category = "contact_rich"
    instruction = "Pick up the green cube from the clutter."
    description = ("Pick the green target object out of a cluttered corral containing "
                   "distractor objects.")
    success_text = ("The green target is lifted at least 0.20 m above its reset height; the "
                    "19 distractor objects are not checked.")
    episode_seconds = 12.0
    deviations = (*LiftTask.deviations,
                  "The corral (0.38 m square inside, 4 cm fence) and the shapes are ours: a "
                  "5 cm green cube among 3.4 cm boxes, 3.6 cm balls and 3.4 cm cylinders, all "
                  "placed without overlap (rejection sampling, 1 cm apart), the target's "
                  "centre at least 7 cm inside the fence.")
    # The target first, then the distractors, each rejection-sampled clear of those
    # placed before it (footprints 1 cm apart): nothing starts interpenetrating.
    placements: ClassVar = {
        "target": Placement(*_TARGET, clearance=0.01),
        **{d: Placement(*_INSIDE, clearance=0.01) for d in DISTRACTORS},
    }
    lifted, lift_threshold = "target", 0.20
    expert = GraspPlan("target")
    layout_tries: ClassVar[int] = 50

    def _place_one(self, rng: np.random.Generator) -> dict[str, np.ndarray]:
        """A whole layout drawn again where one object finds no room: the sampler places
        one object at a time, and an unlucky early layout can leave a late one none."""
        for _ in range(self.layout_tries - 1):
            try:
                return super()._place_one(rng)
            except RuntimeError:
                continue
        return super()._place_one(rng)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"target": lab.add_green_cube(spec, "target"),
                **lab.add_clutter(spec, DISTRACTORS),
                "corral": lab.add_corral(spec, "corral", (*CORRAL_CENTRE, TABLE_TOP_Z),
                                         CORRAL_HALF)}


PLATE_SIZE = (0.08, 0.006, 0.13)  # m: wide, thick, tall; its top 3 cm above the walls
EXTRACT_RISE, EXTRACT_FORWARD = 0.125, 0.05  # m: the goal over the start (forward: -x)


@register
class PickThinObjectFromContainer(TabletopTask):
    name = "PickThinObjectFromContainer"
    category = "contact_rich"
    instruction = "Pull the thin plate out of its container and hold it at the goal."
    description = ("Extract a thin object from a small container and move it to the "
                   "commanded goal.")
    success_text = ("The object's centre comes within 0.04 m of the extraction goal, 0.125 m "
                    "above its start and 0.05 m forward (towards the robot), clear of the "
                    "container's 0.11 m walls.")
    deviations = ("The paper says the goal is pulled forward out of the container without "
                  "a number: 0.05 m towards the robot is ours, as are the plate (8 x 0.6 x "
                  "13 cm, 50 g), the slot (10 x 2.4 cm inside), the container's reset "
                  "ranges (x 0.0..0.1, y -0.15..0.15, yaw +-0.4) and its being fixed to "
                  "the table.",)
    goal_marker = 0.02
    placements: ClassVar = {"container": Placement((0.0, 0.10), (-0.15, 0.15), (-0.4, 0.4))}
    attached: ClassVar = {"plate": ("container", "slot")}
    tolerance = 0.04
    # Pinched by its top edge, the tips levelled where they stand the plate's thickness
    # apart, 2 cm down (1 cm above the walls); lifted clear of them, then carried forward.
    expert = PinchPlan("plate", point="top", depth=0.02, width=PLATE_SIZE[1],
                       lift=EXTRACT_RISE + 0.01, target=task_goal, goal_point="centre")

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"plate": lab.add_thin_plate(spec, "plate", PLATE_SIZE),
                "container": lab.add_slot_container(spec, "container")}

    def sample_reset(self, rngs: list[np.random.Generator]) -> ResetSample:
        """The placements, then the goal: over the plate's start centre, pulled forward."""
        sample = super().sample_reset(rngs)
        start = sample.free_poses[self.objects["plate"].free_joint][:, :3]
        sample.goal = start + [-EXTRACT_FORWARD, 0.0, PLATE_SIZE[2] / 2 + EXTRACT_RISE]
        marker = np.zeros((len(rngs), 7))
        marker[:, :3], marker[:, 3] = sample.goal, 1.0
        sample.mocap_poses[self.markers["goal"].root] = marker
        return sample

    def _miss(self, view: SceneView) -> torch.Tensor:
        return (self.point(view, "plate", "centre") - view.goal[:, :3]).norm(dim=1)

    def success(self, view: SceneView) -> torch.Tensor:
        return self._miss(view) <= self.tolerance

    def progress(self, view: SceneView) -> torch.Tensor:
        return 1.0 - self._miss(view) / 0.3
