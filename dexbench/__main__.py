"""`python -m dexbench ...`: list and inspect tasks and embodiments."""

from dexbench.cli.errors import run_cli
from dexbench.cli.introspect import main

run_cli(main)
