"""Compose arena + embodiment + task objects + sensors into one compiled model."""

from __future__ import annotations

import pathlib
from dataclasses import dataclass

import mujoco

from dexbench.embodiments.builder import add_embodiment, parse_embodiment
from dexbench.embodiments.layout import Embodiment
from dexbench.envs.arena import PhysicsOptions, build_arena
from dexbench.envs.task_api import Task

CONTACT_FORCE_CLIP = 20.0  # N, per fingertip and axis, as the paper's contact group


class InfeasibleTaskError(ValueError):
    """A task and embodiment that cannot go together (e.g. bimanual task, one hand)."""


@dataclass(frozen=True)
class Scene:
    """A compiled scene and the names observation terms need."""

    model: mujoco.MjModel
    embodiment: Embodiment
    options: PhysicsOptions
    contact_sensors: tuple[str, ...]  # one per fingertip, right hand first
    link_sites: tuple[str, ...]  # palm and fingertip sites with pose/velocity sensors
    hand_geoms: tuple[int, ...]  # collision geoms of every hand link


def _link_sensors(spec: mujoco.MjSpec, site: str) -> None:
    for kind in ("framepos", "framequat", "framelinvel", "frameangvel"):
        spec.add_sensor(name=f"{site}:{kind}",
                        type=getattr(mujoco.mjtSensor, f"mjSENS_{kind.upper()}"),
                        objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)


def _contact_sensor(spec: mujoco.MjSpec, obj: str, tip_body: str) -> str:
    """Net force the object exerts on a fingertip, world frame (reduce = netforce)."""
    name = f"{tip_body}:contact"
    spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_BODY, objname=obj,
                    reftype=mujoco.mjtObj.mjOBJ_BODY, refname=tip_body,
                    intprm=[2, 3, 1])  # data = force, reduce = netforce, num = 1
    return name


def compose_scene(task: Task, embodiment: str, options: PhysicsOptions,
                  backgrounds: tuple[pathlib.Path, ...] = ()) -> Scene:
    """Build and compile the scene for a task on an embodiment (`backgrounds`: image files
    background variation may show)."""
    parsed = parse_embodiment(embodiment)
    if task.bimanual and not parsed.bimanual:
        raise InfeasibleTaskError(
            f"{task.name} needs two hands but {embodiment} has one; use "
            f"bimanual_{parsed.mount}_{parsed.hand}"
        )
    spec = build_arena(options, backgrounds)
    plan = add_embodiment(spec, embodiment)
    task.build(spec)
    spec.nuserdata = task.memory_size
    sides = plan.sides.values()
    link_sites = tuple(s for side in sides for s in (side.palm_site, *side.fingertip_sites))
    for site in link_sites:
        _link_sensors(spec, site)
    contacts: tuple[str, ...] = ()
    if task.contact_body is not None:
        contacts = tuple(_contact_sensor(spec, task.contact_body, tip)
                         for side in sides for tip in side.fingertip_bodies)
    model = spec.compile()
    prefixes = tuple(f"{side}/hand/" for side in plan.sides)
    hand_geoms = tuple(
        g for g in range(model.ngeom)
        if model.body(model.geom_bodyid[g]).name.startswith(prefixes)
        and (model.geom_contype[g] or model.geom_conaffinity[g]))
    return Scene(model, Embodiment.resolve(plan, model), options, contacts, link_sites,
                 hand_geoms)
