"""A cordless power drill, the bench stand it hangs in, and a workpiece with a marked point.

The drill is stored as on a workshop rack: hanging bit-down in its stand, the nose collar
resting on a fork and the battery foot on a pad, the grip level on top. A hand holding
the grip from above lifts it out bit-down, its weight hanging below the grip.
"""

from __future__ import annotations

import math

import mujoco

from dexbench.assets.objects import UP, ObjectInfo, Zone, add_geom, free_body, mocap_body
from dexbench.assets.parts import add_visual, zone_body

SHELL = (0.85, 0.45, 0.08, 1.0)  # the orange plastic housing
RUBBER = (0.12, 0.12, 0.13, 1.0)
STEEL = (0.55, 0.57, 0.6, 1.0)
STAND = (0.3, 0.3, 0.32, 1.0)
PLYWOOD = (0.82, 0.68, 0.48, 1.0)
MARK = (0.85, 0.1, 0.1, 1.0)

# The drill, hanging bit-down, in its own frame: the root on the housing's axis at the
# handle's height, the bit along -z, the handle along +x.
# The motor and gearbox housing, its nose down; its back ends level with the grip's axis,
# so a thumb beside the grip does not rest on it.
HOUSING_R, HOUSING_Z = 0.03, (-0.11, 0.0)
COLLAR_R, COLLAR_Z = 0.028, (-0.125, -0.11)  # the clutch ring: rests on the stand's fork
CHUCK_R, CHUCK_Z = 0.017, (-0.17, -0.125)
BIT_R, BIT_Z = 0.003, (-0.245, -0.17)  # a 6 mm bit, 7.5 cm out of the chuck
HANDLE_X, HANDLE_HALF = (0.025, 0.145), (0.015, 0.0175)  # a subcompact's slim grip, 3 x 3.5 cm
# The slide-on battery pack under the grip's end, its back 14 mm short of the grip's
# back (the fingers closing round the grip pass over it).
FOOT_X, FOOT_Z, FOOT_HALF_Y = (0.145, 0.195), (-0.075, 0.005), 0.035
TIP_DEPTH = -BIT_Z[0]  # m: the bit tip below the root
HANG = 0.27  # m: the drill's root above the stand's base (the bit tip 2.5 cm up)


def _span(lo_hi: tuple[float, float]) -> tuple[float, float]:
    """(centre, half extent) of an interval."""
    return (lo_hi[0] + lo_hi[1]) / 2, (lo_hi[1] - lo_hi[0]) / 2


def add_drill(spec: mujoco.MjSpec, name: str, mass: float = 0.95) -> ObjectInfo:
    """A compact 12 V drill driver with its battery pack (0.95 kg, 0.35 of it the pack,
    as such tools weigh): housing, clutch collar, chuck and bit on one axis, the grip
    square to it at the housing's rear and the pack under the grip's end. The pack
    balances the motor, as a drill's is meant to: the drill's weight lies over the grip,
    7 cm out from the bit's axis.

    The chuck (body `<name>/chuck`) and the bit (`<name>/bit`) are the no-touch parts.
    Points: `grip` (on the grip's axis, over the weight), `tip` (the bit's point),
    `chuck`. Axes: `bit` (chuck to tip), `up` (tip to the housing's rear).
    """
    body = free_body(spec, name)
    z, half = _span(HOUSING_Z)
    add_geom(body, f"{name}/housing", "cylinder", [HOUSING_R, half], SHELL, 0.38 * mass,
             pos=[0, 0, z])
    z, half = _span(COLLAR_Z)
    add_geom(body, f"{name}/collar", "cylinder", [COLLAR_R, half], RUBBER, 0.03 * mass,
             pos=[0, 0, z])
    x, hx = _span(HANDLE_X)
    add_geom(body, f"{name}/grip", "box", [hx, *HANDLE_HALF], RUBBER, 0.115 * mass,
             pos=[x, 0, 0])
    fx, fhx = _span(FOOT_X)
    fz, fhz = _span(FOOT_Z)
    add_geom(body, f"{name}/foot", "box", [fhx, FOOT_HALF_Y, fhz], SHELL, 0.37 * mass,
             pos=[fx, 0, fz])
    cz, chalf = _span(CHUCK_Z)
    chuck = zone_body(body, f"{name}/chuck", (0.0, 0.0, cz))
    add_geom(chuck, f"{name}/chuck", "cylinder", [CHUCK_R, chalf], STEEL, 0.095 * mass)
    bz, bhalf = _span(BIT_Z)
    bit = zone_body(body, f"{name}/bit", (0.0, 0.0, bz))
    add_geom(bit, f"{name}/bit", "cylinder", [BIT_R, bhalf], STEEL, 0.01 * mass)
    margin = 0.005  # the zones stand this far clear of the parts, as the nail head's
    return ObjectInfo(name, name, f"{name}/free", False, 0.0, math.hypot(FOOT_X[1], 0.03),
                      points={"grip": (name, (0.07, 0.0, 0.0)),
                              "tip": (f"{name}/bit", (0.0, 0.0, -bhalf)),
                              "chuck": (f"{name}/chuck", (0.0, 0.0, 0.0))},
                      axes={"bit": (name, (0.0, 0.0, -1.0)), "up": (name, UP)},
                      zones=(Zone(f"{name}/chuck", "cylinder", (0.0, 0.0, 0.0),
                                  CHUCK_R + margin, chalf + margin),
                             Zone(f"{name}/bit", "cylinder", (0.0, 0.0, 0.0),
                                  BIT_R + margin, bhalf + margin)))


def add_drill_stand(spec: mujoco.MjSpec, name: str) -> ObjectInfo:
    """The stand (fixed) an `add_drill` drill hangs in, bit-down: a fork under the
    collar (the chuck between its prongs) on a post behind it, and a pad under the
    battery foot, on one base plate; the drill lifts straight up out of it.

    The stand's root is the middle of its base plate. Point `drill` is where the drill's
    root goes, turned like the stand (the grip along the stand's +x).
    """
    base = mocap_body(spec, name)
    axis = -0.055  # the drill's axis, from the base plate's middle
    fork_top = HANG + COLLAR_Z[0]
    add_geom(base, f"{name}/base", "box", [0.12, 0.04, 0.003], STAND, pos=[0, 0, 0.003])
    prong_y = CHUCK_R + 0.004 + 0.004  # 4 mm clear of the chuck, 8 mm wide
    for k, y in enumerate((prong_y, -prong_y)):
        add_geom(base, f"{name}/prong{k}", "box", [0.035, 0.004, 0.006], STAND,
                 pos=[axis - 0.005, y, fork_top - 0.006])
    add_geom(base, f"{name}/post", "box", [0.012, prong_y + 0.004, fork_top / 2], STAND,
             pos=[axis - 0.047, 0, fork_top / 2])
    pad_top = HANG + FOOT_Z[0]
    fx, _ = _span(FOOT_X)
    add_geom(base, f"{name}/pad", "box", [0.015, 0.02, pad_top / 2], STAND,
             pos=[axis + fx, 0, pad_top / 2])
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(0.12, 0.04),
                      points={"drill": (name, (axis, 0.0, HANG)),
                              "fork": (name, (axis, 0.0, fork_top))})


def add_workpiece(spec: mujoco.MjSpec, name: str, half: float = 0.08,
                  thickness: float = 0.018) -> ObjectInfo:
    """A plywood board (fixed) with a drilling mark (a red dot, decoration) at its centre.

    Point `mark` is the mark on the board's top face.
    """
    base = mocap_body(spec, name)
    add_geom(base, f"{name}/board", "box", [half, half, thickness / 2], PLYWOOD,
             pos=[0, 0, thickness / 2])
    add_visual(base, f"{name}/mark", "cylinder", [0.006, 0.0005], MARK,
               pos=[0, 0, thickness + 0.0005])
    return ObjectInfo(name, name, None, True, 0.0, math.hypot(half, half),
                      points={"mark": (name, (0.0, 0.0, thickness))},
                      axes={"up": (name, UP)})
