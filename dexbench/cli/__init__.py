"""Command-line entry points: thin Hydra mains (`app.py`) that turn a config into a call."""
