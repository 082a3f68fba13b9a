"""Command-line entry points (thin Hydra-composed mains)."""
