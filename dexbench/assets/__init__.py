"""Robot model assets: where arm and hand MJCF files come from."""
