"""`python -m dexbench ...`: list, inspect, snapshot, docs, validate, merge and split."""

from dexbench.cli.introspect import entry

entry()
