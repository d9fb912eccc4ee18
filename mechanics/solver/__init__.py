"""All feasible contact modes of a scene: the batched test (eqs. 24-28), chunks, and the exact pruned search."""
