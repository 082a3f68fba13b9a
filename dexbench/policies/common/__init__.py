"""Pieces every learned policy shares: the protocol, normalizers, chunking, EMA, checkpoints."""
