"""Policy kinds by name, imported lazily so that a missing optional extra stays local.

Each kind's module provides `spec(checkpoint, options) -> PolicySpec` (read before the
env is built, so the env gets the right observation preset and cameras) and
`build(checkpoint, env, device, options) -> Policy`; `options` is the kind's
`conf/policy/<kind>.yaml` (with overrides) as a dict, which checkpointed kinds ignore
(their checkpoint holds what they need).
"""

from __future__ import annotations

import importlib
from types import ModuleType

KINDS = {
    "dp": "dexbench.policies.dp.policy",
    "dp3": "dexbench.policies.dp3.policy",
    "expert": "dexbench.policies.expert",
    "lerobot": "dexbench.policies.vla_adapters.lerobot_policy",
    "openpi": "dexbench.policies.vla_adapters.openpi",
    "openvla_oft": "dexbench.policies.vla_adapters.openvla_oft",
    "rl": "dexbench.policies.rl",
}
# Kinds whose model another program serves; their settings say what it is sent.
SERVED = frozenset({"openpi", "openvla_oft"})
# Kinds whose settings, not a checkpoint, say which model runs (a resumed evaluation must
# keep them): served kinds, and LeRobot policies loaded from `policy.path`.
BY_SETTINGS = SERVED | {"lerobot"}
# Kinds that take no checkpoint= (scripted, served, or loaded from their settings).
WITHOUT_CHECKPOINT = BY_SETTINGS | {"expert"}


def policy_module(kind: str) -> ModuleType:
    """The module implementing policy `kind`, or an error listing the known kinds."""
    if kind not in KINDS:
        raise ValueError(f"unknown policy {kind!r}; choose one of {', '.join(sorted(KINDS))}")
    return importlib.import_module(KINDS[kind])
