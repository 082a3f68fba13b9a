"""`python -m dexbench ...`: list, inspect, snapshot, docs and validate."""

from dexbench.cli.errors import run_cli
from dexbench.cli.introspect import main

run_cli(main)
