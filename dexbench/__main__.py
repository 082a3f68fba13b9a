"""`python -m dexbench ...`: list, inspect, snapshot, docs, validate and merge."""

from dexbench.cli.errors import run_cli
from dexbench.cli.introspect import main
from dexbench.cli.merge import merge

run_cli(lambda argv: merge(argv[1:]) if argv[:1] == ["merge"] else main(argv))
