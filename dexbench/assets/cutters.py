"""Hand tools with moving blades: a utility knife (slide) and scissors (two hinges).

Both lie flat with their blades towards +x. Joints are named `<name>/<joint>`; the
blades' friction loss holds them where a hand leaves them.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.objects import UP, ObjectInfo, add_geom, free_body
from dexbench.assets.parts import add_joint, add_visual

HANDLE = (0.95, 0.75, 0.1, 1.0)
BLADE = (0.8, 0.82, 0.86, 1.0)
DARK = (0.15, 0.15, 0.17, 1.0)


def add_utility_knife(spec: mujoco.MjSpec, name: str, travel: float = 0.035,
                      mass: float = 0.11) -> ObjectInfo:
    """A utility knife (0.15 x 0.026 x 0.02 m handle) whose blade slides out along +x.

    Joint `<name>/blade` is 0 retracted (the blade tip just inside the handle) and
    `travel` fully out; a thumb knob on top of the handle moves with the blade. Friction
    loss (0.4 N) holds the blade against its weight whichever way the knife points.
    Points: `slider` (knob top), `blade_tip`, `grip` (handle centre), `tail`.
    Axes: `up`, `blade` (the sliding direction).
    """
    hx, hy, hz = 0.075, 0.013, 0.01
    body = free_body(spec, name)
    add_geom(body, f"{name}/handle", "box", [hx, hy, hz], HANDLE, 0.9 * mass, pos=[0, 0, hz])
    add_visual(body, f"{name}/slot", "box", [0.03, 0.003, 5e-4], DARK,
               pos=[0.0, 0, 2 * hz + 2e-4])
    blade = body.add_body(name=f"{name}/blade", pos=[0, 0, hz])
    joint = add_joint(blade, f"{name}/blade", "slide", (1.0, 0.0, 0.0), (0.0, travel), 2.0,
                      0.4)
    half_len = 0.025
    tip_x = hx - 0.002
    add_geom(blade, f"{name}/blade", "box", [half_len, 0.0008, 0.006], BLADE, 0.06 * mass,
             pos=[tip_x - half_len, 0, 0])
    knob = (-0.02, 0.0, hz + 0.003)
    add_geom(blade, f"{name}/knob", "box", [0.007, 0.005, 0.004], DARK, 0.04 * mass,
             pos=list(knob))
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, math.hypot(hx, hy),
                      joints={joint: (0.0, travel)},
                      points={"slider": (f"{name}/blade", (knob[0], 0.0, knob[2] + 0.004)),
                              "blade_tip": (f"{name}/blade", (tip_x, 0.0, 0.0)),
                              "grip": (name, (-0.02, 0.0, hz)),
                              "tail": (name, (-hx, 0.0, hz))},
                      axes={"up": (name, UP), "blade": (name, (1.0, 0.0, 0.0))})


def _finger_ring(body: mujoco.MjsBody, name: str, centre: tuple[float, float], radius: float,
                 tube: float, mass: float, sides: int = 8) -> None:
    """A flat finger loop: `sides` capsules around `centre` (in the body's z = 0 plane)."""
    cx, cy = centre
    corners = [(cx + radius * math.cos(2 * math.pi * k / sides),
                cy + radius * math.sin(2 * math.pi * k / sides)) for k in range(sides + 1)]
    for k in range(sides):
        (x0, y0), (x1, y1) = corners[k], corners[k + 1]
        add_geom(body, f"{name}{k}", "capsule", [tube], HANDLE, mass / sides,
                 fromto=[x0, y0, 0.0, x1, y1, 0.0])


def add_scissors(spec: mujoco.MjSpec, name: str, opening: float = math.radians(20.0),
                 mass: float = 0.08) -> ObjectInfo:
    """Scissors lying flat: a pivot (the free root) and two blades, each on its own hinge.

    Joints `<name>/blade0` (the blade on the +y side) and `<name>/blade1` are each
    blade's half-opening angle about the pivot's vertical axis: 0 closed, `opening` wide
    open; squeezing the finger rings together closes both. The two blades lie in one
    plane and overlap near the pivot as a real pair does, so contacts between them are
    excluded (the joint limits keep them from crossing). The scissors rest on the pivot
    and both rings, 1 cm thick. Points: `ring0`, `ring1` (finger-loop centres), `tip0`,
    `tip1` (blade tips), `pivot`. Axis `up` (the hinge axis).
    """
    tube = 0.005
    pivot = free_body(spec, name)
    add_geom(pivot, f"{name}/pivot", "cylinder", [0.007, tube], DARK, 0.1 * mass)
    points = {"pivot": (name, (0.0, 0.0, 0.0))}
    joints = {}
    for k, side in enumerate((1.0, -1.0)):
        blade = pivot.add_body(name=f"{name}/blade{k}")
        joint = add_joint(blade, f"{name}/blade{k}", "hinge", (0.0, 0.0, side),
                          (0.0, opening), 0.002, 0.005)
        joints[joint] = (0.0, opening)
        add_geom(blade, f"{name}/blade{k}", "box", [0.045, 0.005, 0.002], BLADE,
                 0.2 * mass, pos=[0.05, side * 0.002, 0])
        ring = (-0.062, -side * 0.022)
        add_geom(blade, f"{name}/shank{k}", "capsule", [0.004], HANDLE, 0.05 * mass,
                 fromto=[0.0, 0.0, 0.0, ring[0] + 0.016, ring[1] * 0.6, 0.0])
        _finger_ring(blade, f"{name}/ring{k}_", ring, 0.016, tube, 0.2 * mass)
        points[f"ring{k}"] = (f"{name}/blade{k}", (*ring, 0.0))
        points[f"tip{k}"] = (f"{name}/blade{k}", (0.095, side * 0.002, 0.0))
    spec.add_exclude(bodyname1=f"{name}/blade0", bodyname2=f"{name}/blade1")
    reach = max(math.hypot(0.062, 0.022) + 0.016 + tube, math.hypot(0.095, 0.007))
    return ObjectInfo(name, name, f"{name}/free", False, tube, reach, joints=joints,
                      points=points, axes={"up": (name, UP)})
