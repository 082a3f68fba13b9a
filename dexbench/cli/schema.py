"""Typed config nodes in Hydra's ConfigStore: the one place their defaults live.

The library's own dataclasses hold the defaults (`VisualVariation`, `PhysicalVariation`,
`PhysicsOptions`); here each becomes a mutable schema with the same
fields, types and defaults (OmegaConf makes frozen dataclasses read-only, and overrides
must merge into them). conf/visual/*.yaml, conf/physical/*.yaml and `sim`
start from these nodes and set only what differs, and Hydra checks every override's key
and type against them.
"""

from __future__ import annotations

import dataclasses
import typing

from hydra.core.config_store import ConfigStore

from dexbench.envs.arena import PhysicsOptions
from dexbench.envs.variation import PhysicalVariation, VisualVariation


def schema_of(cls: type, name: str, extra: tuple = ()) -> type:
    """A mutable dataclass `name` with `cls`'s fields and defaults, then `extra` ones
    (`(name, type, dataclasses.field(...))` triples)."""
    hints = typing.get_type_hints(cls)
    own = [(f.name, hints[f.name], dataclasses.field(default=f.default))
           for f in dataclasses.fields(cls)]
    return dataclasses.make_dataclass(name, [*extra, *own])


VisualSchema = schema_of(VisualVariation, "VisualSchema")
PhysicalSchema = schema_of(PhysicalVariation, "PhysicalSchema")
SimSchema = schema_of(PhysicsOptions, "SimSchema", (
    ("backend", str, dataclasses.field(default="cpu")),  # cpu (mujoco.batch) or warp (GPU)
    ("nthread", int, dataclasses.field(default=0)),  # cpu backend threads; 0: one per core
))


def physics_options(sim) -> PhysicsOptions:
    """`PhysicsOptions` from a `sim` node (keys it lacks keep their defaults)."""
    names = {f.name for f in dataclasses.fields(PhysicsOptions)}
    return PhysicsOptions(**{k: v for k, v in sim.items() if k in names})


def register() -> None:
    """Store the nodes (idempotent): `visual/base`, `physical/base`, `sim_base` (package
    `sim`)."""
    cs = ConfigStore.instance()
    cs.store(group="visual", name="base", node=VisualSchema)
    cs.store(group="physical", name="base", node=PhysicalSchema)
    cs.store(name="sim_base", package="sim", node=SimSchema)


register()
