"""optim/discrete."""
