"""Physics backends behind one batched interface (see `backend.SimBackend`)."""
