"""Small building blocks shared by the tool, office and kitchen objects.

`add_joint` gives every mechanism joint a limited range, damping, and friction loss so a
part stays where a hand leaves it. Friction loss and limits use impedance `GRIP`, not
`articulated.HOLD`: at HOLD's 0.999 MuJoCo's Newton solver lets a friction-held light
part (stapler arm, folder flap, knife blade) chatter on after a knock, never coming to
rest, and 0.995 does not; with MuJoCo's default limit impedance and time constant a
stapler arm slammed shut went 5 deg into its base, hence `STOP` as well.

No-touch zones: a zone's `body` is a jointless child body (`zone_body`) that holds
exactly the geoms a hand must not touch (spout, nozzle, lip, cooking surface, nail
head). A task can then test contacts with that body's geoms, or the zone volume.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco

GRIP = [0.995, 0.995, 0.001, 0.5, 2.0]  # solimp of friction loss and limits
STOP = [0.01, 1.0]  # limit time constant: half MuJoCo's default, still >= 2 timesteps


def add_joint(body: mujoco.MjsBody, name: str, kind: str, axis: Sequence[float],
              limits: tuple[float, float], damping: float, friction: float,
              armature: float = 1e-3) -> str:
    """A limited hinge or slide joint (`kind`), held by friction loss where it is left."""
    body.add_joint(name=name, type=getattr(mujoco.mjtJoint, f"mjJNT_{kind.upper()}"),
                   axis=list(axis), range=list(limits), damping=damping,
                   frictionloss=friction, armature=armature, solimp_friction=GRIP,
                   solimp_limit=GRIP, solref_limit=STOP)
    return name


def zone_body(parent: mujoco.MjsBody, name: str, pos: Sequence[float]) -> mujoco.MjsBody:
    """A jointless child body (rigid with its parent) for the geoms of one no-touch zone."""
    return parent.add_body(name=name, pos=list(pos))


def add_visual(body: mujoco.MjsBody, name: str, kind: str, size: Sequence[float],
               rgba: Sequence[float], **kw) -> mujoco.MjsGeom:
    """A massless, non-colliding decoration (group 2, like other visual-only geoms)."""
    return body.add_geom(name=name, type=getattr(mujoco.mjtGeom, f"mjGEOM_{kind.upper()}"),
                         size=list(size), rgba=list(rgba), contype=0, conaffinity=0,
                         group=2, mass=0.0, **kw)
