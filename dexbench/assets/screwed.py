"""Screwed parts: a tube standing in a stand, its cap screwed onto its neck.

The stand is fixed (the paper's "hold the tube": a fixate task, the base held for the
hand); the cap turns about the tube's axis (+z) from 0, screwed in, to `turns` full
turns, where its thread runs out and it is loose on the neck. Grip fins stand out round
the cap's rim, for fingers to push it round by.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.articulated import ACCENT, GREY
from dexbench.assets.objects import ObjectInfo, add_geom, mocap_body
from dexbench.assets.parts import add_joint

TUBE = (0.92, 0.92, 0.88, 1.0)


def add_capped_tube(spec: mujoco.MjSpec, name: str, turns: float = 1.0, radius: float = 0.016,
                    height: float = 0.10, fins: int = 4) -> ObjectInfo:
    """A tube (`radius` 1.6 cm, `height` 10 cm, like a 50 ml sample tube) upright in a
    6 cm square stand 1 cm tall, and its screw cap: 2 cm tall, 2 mm wider than the tube,
    with `fins` fins 4 mm thick and 18 mm tall out to 3 cm from the axis round its rim,
    moulded plastic, 15 g in all.

    The thread turns easily once loosened but drags: damping 0.002 N m s/rad, friction
    loss 0.02 N m, so the cap stays where it is left; the inertia added to the joint
    (armature) is only 1e-5 kg m^2, near the light cap's own (~2e-6): with the default
    1e-3 a flick would spin it on like a flywheel. The thread's rise (a few mm over the
    travel) is left out: the cap turns in place. Point `fin` is the outer edge of the fin
    along the cap's local +x, half-way up it.
    """
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/stand", "box", [0.03, 0.03, 0.005], GREY, pos=[0, 0, 0.005])
    add_geom(base, f"{name}/tube", "cylinder", [radius, height / 2], TUBE,
             pos=[0, 0, 0.01 + height / 2])
    cap = base.add_body(name=f"{name}/cap", pos=[0, 0, 0.01 + height])
    travel = (0.0, 2 * math.pi * turns)
    joint = add_joint(cap, f"{name}/thread", "hinge", (0, 0, 1), travel, 0.002, 0.02,
                      armature=1e-5)
    add_geom(cap, f"{name}/shell", "cylinder", [radius + 0.002, 0.01], ACCENT, 0.01,
             pos=[0, 0, 0.01])
    reach = 0.03
    mid = (radius + reach) / 2
    for k in range(fins):
        angle = 2 * math.pi * k / fins
        add_geom(cap, f"{name}/fin{k}", "box", [reach - mid, 0.002, 0.009], ACCENT,
                 0.005 / fins, pos=[mid * math.cos(angle), mid * math.sin(angle), 0.01],
                 euler=[0, 0, angle])
    return ObjectInfo(name, name, None, True, 0.0, 0.045, joints={joint: travel},
                      points={"fin": (f"{name}/cap", (reach, 0.0, 0.01))})
