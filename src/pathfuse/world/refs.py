"""Online versions of the reference methods [6] and [7] (placeholder until written)."""
