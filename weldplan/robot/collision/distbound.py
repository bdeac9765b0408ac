"""The part's distance table, now shared with the tool's swept check: see
:mod:`weldplan.geometry.distbound` (kept here so that existing imports keep working)."""

from weldplan.geometry.distbound import BLOCK, MAX_NODES, MIN_CELL_MM, PAD_MM, DistanceBound

__all__ = ["BLOCK", "MAX_NODES", "MIN_CELL_MM", "PAD_MM", "DistanceBound"]
