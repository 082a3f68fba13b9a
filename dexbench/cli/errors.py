"""Turn expected user errors into one clear line and exit code 2, not a traceback."""

from __future__ import annotations

import sys
from collections.abc import Callable

from dexbench.assets.robots import ChecksumMismatchError, MissingRobotModelError
from dexbench.cli.config import ConfigError
from dexbench.data.meta import DatasetError
from dexbench.embodiments.builder import UnknownEmbodimentError
from dexbench.envs.dex_env import InvalidActionError
from dexbench.envs.scene import InfeasibleTaskError
from dexbench.eval.session import EvalError
from dexbench.policies.vla_adapters.chunks import RemotePolicyError
from dexbench.tasks.registry import UnknownTaskError

USER_ERRORS = (ConfigError, UnknownTaskError, UnknownEmbodimentError, InfeasibleTaskError,
               MissingRobotModelError, ChecksumMismatchError, InvalidActionError,
               DatasetError, RemotePolicyError, EvalError, NotImplementedError)


def run_cli(main: Callable[[list[str]], int]) -> None:
    """Run `main(sys.argv[1:])`, printing user errors as `error: ...`."""
    try:
        code = main(sys.argv[1:])
    except USER_ERRORS as err:
        print(f"error: {err}", file=sys.stderr)
        code = 2
    sys.exit(code)
