"""planar."""
