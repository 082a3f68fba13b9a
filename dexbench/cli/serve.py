"""`python -m dexbench serve policy=<dp|dp3|rl> checkpoint=<path> [host=...] [port=...]`:
a checkpoint behind openpi's websocket protocol (`dexbench/policies/serving.py` documents
the schema), until interrupted. Writes nothing."""

from __future__ import annotations

import json
import pathlib
import sys

from omegaconf import DictConfig

from dexbench.cli.app import Command, register
from dexbench.cli.config import ConfigError
from dexbench.policies.serving import PolicyServer, Served, load_served, unservable


def _check(cfg: DictConfig, overrides: list[str]) -> Served:
    """The loaded model: a bad kind or checkpoint is one error line before serving."""
    kind = str(cfg.policy.name)
    why = unservable(kind)
    if why:
        raise ConfigError(why)
    if cfg.checkpoint is None:
        raise ConfigError(f"serve policy={kind} needs checkpoint=<a .pt file or training "
                          "run folder>")
    if not 0 <= int(cfg.port) < 65536:
        raise ConfigError(f"port must be in 0..65535, got {cfg.port}")
    try:
        return load_served(kind, str(cfg.checkpoint), str(cfg.device))
    except ValueError as err:
        raise ConfigError(str(err)) from None


def _run(cfg: DictConfig, served: Served, _out: pathlib.Path | None) -> int:
    try:
        server = PolicyServer(served, str(cfg.host), int(cfg.port), int(cfg.seed))
    except OSError as err:
        raise ConfigError(f"cannot listen on {cfg.host}:{cfg.port} ({err}); pick another "
                          "port=") from None
    meta = served.metadata
    print(f"serving {meta['kind']} ({meta['task']}, {meta['embodiment']}) on "
          f"ws://{cfg.host}:{server.port}", file=sys.stderr)
    print(json.dumps({"port": server.port, **meta}), flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        server.shutdown()
    return 0


SERVE = register(Command("serve", _run, _check))
serve = SERVE.main
