"""InsertPipette: guide a Pasteur pipette's tip into an Erlenmeyer flask's neck."""

from __future__ import annotations

from typing import ClassVar

import mujoco

from dexbench.assets import lab
from dexbench.assets.objects import ObjectInfo
from dexbench.tasks.catalog import register
from dexbench.tasks.contact_rich import SlenderInsertTask, pinch_and_insert
from dexbench.tasks.templates import Placement

PIPETTE_RAISED = 0.2  # m: high enough for the pipette, turned tip-down, to clear the flask


# InsertPen's plan kind on the pipette: pinched across the barrel just below the bulb (the
# wider bulb then rests on the tips if the pipette, hanging tip-down, starts to slide),
# lifted, turned tip-down over the neck and lowered in.
PIPETTE_PLAN = pinch_and_insert("pipette", "flask", ("bulb_end", (0.04, 0.0, 0.0)),
                                PIPETTE_RAISED)


@register
class InsertPipette(SlenderInsertTask):
    name = "InsertPipette"
    category = "contact_rich"
    instruction = "Put the pipette's tip into the neck of the flask."
    description = ("Pick up a pipette and guide its tip into the neck of the target "
                   "glassware.")
    success_text = ("The pipette tip is centred within 0.02 m (horizontally) of the flask "
                    "opening and at least 0.01 m below its rim.")
    episode_seconds = 25.0
    deviations = ("The paper gives no reset ranges: the pipette's (x -0.30..-0.20) and the "
                  "flask's (x 0.15..0.20), both y -0.15..0.15, are ours (InsertPen's); the "
                  "flask is clamped in place (fixed), like InsertPen's holder.",)
    placements: ClassVar = {
        "pipette": Placement((-0.30, -0.20), (-0.15, 0.15)),
        "flask": Placement((0.15, 0.20), (-0.15, 0.15), clearance=0.05),
    }
    centred, below = 0.02, 0.01
    expert = PIPETTE_PLAN
    slender, holder, ends = "pipette", "flask", ("tip",)

    def make_objects(self, spec: mujoco.MjSpec) -> dict[str, ObjectInfo]:
        return {"pipette": lab.add_pipette(spec, "pipette"),
                "flask": lab.add_flask(spec, "flask")}
