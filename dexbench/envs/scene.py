"""Compose arena + embodiment + task objects + sensors into one compiled model."""

from __future__ import annotations

import pathlib
from dataclasses import dataclass, replace

import mujoco

from dexbench.assets.objects import Zone
from dexbench.embodiments.builder import SideLayout, add_embodiment, parse_embodiment
from dexbench.embodiments.layout import Embodiment
from dexbench.envs.arena import PhysicsOptions, build_arena
from dexbench.envs.task_api import ZONE_CONTACTS, Task, link_force_key, touch_key, zone_key

CONTACT_FORCE_CLIP = 20.0  # N, per fingertip and axis, as the paper's contact group


class InfeasibleTaskError(ValueError):
    """A task and embodiment that cannot go together (e.g. bimanual task, one hand)."""


def _hands(bimanual: bool) -> str:
    return "two hands" if bimanual else "one hand"


def pair_problem(task: Task | type[Task], embodiment: str) -> str | None:
    """Why `task` cannot run on `embodiment` (it has another number of hands: a second
    hand on a single-hand task would have no defined role), or None when it can."""
    parsed = parse_embodiment(embodiment)
    if task.bimanual == parsed.bimanual:
        return None
    other = replace(parsed, bimanual=task.bimanual)
    return (f"needs {_hands(task.bimanual)}; embodiment {embodiment} has "
            f"{_hands(parsed.bimanual)}: use embodiment={other}")


def check_pair(task: Task | type[Task], embodiment: str) -> None:
    """The one rule on task x embodiment pairs: every command that builds a scene (and
    eval's planning, before a run starts) goes through it."""
    problem = pair_problem(task, embodiment)
    if problem is not None:
        raise InfeasibleTaskError(f"{task.name} {problem}")


@dataclass(frozen=True)
class Scene:
    """A compiled scene and the names observation terms need."""

    model: mujoco.MjModel
    embodiment: Embodiment
    options: PhysicsOptions
    contact_sensors: tuple[str, ...]  # per fingertip (right hand first), one per
    # contact body of the task
    link_sites: tuple[str, ...]  # palm and fingertip sites with pose/velocity sensors
    hand_geoms: tuple[int, ...]  # collision geoms of every hand link
    # (object, side) -> sensors of the force the object exerts on each of that hand's
    # links, in model order (`SceneView.link_forces`)
    link_force_sensors: dict[tuple[str, str], tuple[str, ...]]


def _link_sensors(spec: mujoco.MjSpec, site: str) -> None:
    for kind in ("framepos", "framequat", "framelinvel", "frameangvel"):
        spec.add_sensor(name=f"{site}:{kind}",
                        type=getattr(mujoco.mjtSensor, f"mjSENS_{kind.upper()}"),
                        objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)


def _contact_sensor(spec: mujoco.MjSpec, obj: str, tip_body: str) -> str:
    """Net force the subtree of body `obj` (the object and its moving parts) exerts on a
    fingertip, world frame (reduce = netforce)."""
    name = f"{tip_body}:contact:{obj}"
    spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_XBODY, objname=obj,
                    reftype=mujoco.mjtObj.mjOBJ_BODY, refname=tip_body,
                    intprm=[2, 3, 1])  # data = force, reduce = netforce, num = 1
    return name


def _zone_sensor(spec: mujoco.MjSpec, zone: Zone, side: SideLayout) -> None:
    """Contacts between a hand (its whole subtree) and a no-touch zone's body: found and
    position of the deepest `ZONE_CONTACTS` (`SceneView.zone_contacts` reads them)."""
    spec.add_sensor(name=f"{zone_key(zone)}:{side.side}", type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_BODY, objname=zone.body,
                    reftype=mujoco.mjtObj.mjOBJ_XBODY, refname=side.hand_root,
                    intprm=[1 | 16, 1, ZONE_CONTACTS])  # found + pos, reduce = mindist


def _link_force_sensor(spec: mujoco.MjSpec, obj: str, link: str) -> str:
    """Net force the subtree of body `obj` exerts on the hand link `link`, world frame
    (`SceneView.link_forces` reads them)."""
    spec.add_sensor(name=link_force_key(link, obj), type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_XBODY, objname=obj,
                    reftype=mujoco.mjtObj.mjOBJ_BODY, refname=link,
                    intprm=[2, 3, 1])  # data = force, reduce = netforce, num = 1
    return link_force_key(link, obj)


def _touch_sensor(spec: mujoco.MjSpec, a: str, b: str) -> None:
    """Whether the subtrees of bodies `a` and `b` touch (`SceneView.touching`)."""
    spec.add_sensor(name=touch_key(a, b), type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_XBODY, objname=a,
                    reftype=mujoco.mjtObj.mjOBJ_XBODY, refname=b,
                    intprm=[1, 1, 1])  # data = found, reduce = mindist, num = 1


def compose_scene(task: Task, embodiment: str, options: PhysicsOptions,
                  backgrounds: tuple[pathlib.Path, ...] = ()) -> Scene:
    """Build and compile the scene for a task on an embodiment (`backgrounds`: image files
    background variation may show)."""
    check_pair(task, embodiment)
    spec = build_arena(options, backgrounds)
    plan = add_embodiment(spec, embodiment, task.workspace)
    task.build(spec)
    spec.nuserdata = task.memory_size
    sides = plan.sides.values()
    link_sites = tuple(s for side in sides for s in (side.palm_site, *side.fingertip_sites))
    for site in link_sites:
        _link_sensors(spec, site)
    contacts = tuple(_contact_sensor(spec, body, tip) for side in sides
                     for tip in side.fingertip_bodies for body in task.contact_bodies)
    for zone in dict.fromkeys(task.zones):
        for side in sides:
            _zone_sensor(spec, zone, side)
    prefixes = tuple(f"{side}/hand/" for side in plan.sides)
    link_forces = {}
    if task.link_force_bodies:
        for side, prefix in zip(plan.sides, prefixes, strict=True):
            links = [b.name for b in spec.bodies
                     if b.first_geom() is not None and b.name.startswith(prefix)]
            for obj in dict.fromkeys(task.link_force_bodies):
                link_forces[obj, side] = tuple(_link_force_sensor(spec, obj, link)
                                               for link in links)
    for a, b in dict.fromkeys(task.touch_pairs):
        _touch_sensor(spec, a, b)
    model = spec.compile()
    hand_geoms = tuple(
        g for g in range(model.ngeom)
        if model.body(model.geom_bodyid[g]).name.startswith(prefixes)
        and (model.geom_contype[g] or model.geom_conaffinity[g]))
    return Scene(model, Embodiment.resolve(plan, model), options, contacts, link_sites,
                 hand_geoms, link_forces)
