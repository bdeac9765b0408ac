"""Discrete optimisation: ant colony on grids (:mod:`.aco_grid`) and the sequencer (TSP-PSO,
Held-Karp, 2-opt/Or-opt polish).

``solve_sequence(cost)`` orders the nodes of any cost matrix; see
:mod:`weldplan.optim.discrete.sequence`.
"""

from weldplan.optim.discrete.costs import cost_matrix, euclidean
from weldplan.optim.discrete.local_search import PolishParams
from weldplan.optim.discrete.sequence import Sequence, SequenceSettings, solve_sequence
from weldplan.optim.discrete.tsp_pso import PSOParams

__all__ = [
    "PSOParams",
    "PolishParams",
    "Sequence",
    "SequenceSettings",
    "cost_matrix",
    "euclidean",
    "solve_sequence",
]
