"""Benchmark tasks, one module per category; `registry` finds them by name."""
