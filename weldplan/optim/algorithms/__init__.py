"""optim/algorithms."""
