"""Held-Karp dynamic programming: the exact shortest closed tour, vectorised over subsets.

Held, M. and Karp, R. M. (1962), "A dynamic programming approach to sequencing problems",
J. SIAM 10(1): for a tour starting at node ``s`` over the other ``k = m - 1`` nodes,

    D[S, j] = min_{i in S \\ {j}} D[S \\ {j}, i] + A[i, j]        (S a subset containing j)
    D[{j}, j] = A[s, j]
    optimum  = min_j D[all, j] + A[j, s]

The table ``D`` is a ``(2^k, k) float64`` array indexed by bitmask. Subsets are processed level by
level (by size); within a level, for each last node ``j`` the recurrence is one numpy ``min`` over
an ``(n_subsets, k)`` block, so the work is ``O(2^k k^2)`` flops in ``O(k^2)`` numpy calls. The
tour is recovered by re-running the argmin backwards, so no parent table is stored.

Time and memory (measured in ``weldplan bench sequence --held-karp``): the table takes
``8 k 2^k`` bytes (17 nodes: 17 MB; 20 nodes: 168 MB; 23 nodes: 1.5 GB) and the time grows like
``k^2 2^k``; beyond about 20 nodes use the swarm plus polish. :data:`MAX_NODES` guards it.
Every sequencing variant reaches this module as a closed tour (see
:mod:`weldplan.optim.discrete.costs`); ``inf`` costs are handled exactly (an infeasible instance
returns ``inf``).
"""

from __future__ import annotations

import logging

import numpy as np
from numpy.typing import NDArray

log = logging.getLogger(__name__)

#: Largest tour (``m`` nodes, start included) the solver accepts: ``2^(m-1) (m-1)`` float64
#: entries: 168 MB at 21 nodes (an open path of 20 joints), 2.6 GB at 24. Raise it knowingly.
MAX_NODES = 21


def _levels(k: int) -> list[NDArray[np.int64]]:
    """Bitmasks over ``k`` bits grouped by popcount: ``levels[c]`` holds the masks of size ``c``."""
    masks = np.arange(1 << k, dtype=np.int64)
    counts = np.bitwise_count(masks)
    order = np.argsort(counts, kind="stable")
    bounds = np.searchsorted(counts[order], np.arange(k + 2))
    return [masks[order[bounds[c] : bounds[c + 1]]] for c in range(k + 1)]


def held_karp_tour(A: NDArray[np.float64], start: int = 0) -> tuple[NDArray[np.intp], float]:
    """Exact minimum-cost closed tour over ``A`` starting at ``start``.

    Parameters
    ----------
    A
        ``(m, m) float``: cost of each directed edge; ``inf`` marks a forbidden edge. The
        diagonal is ignored.
    start
        The node the tour starts (and ends) at.

    Returns
    -------
    tour, cost
        ``(m,) int`` node order beginning with ``start``, and its cost (``inf`` when no tour of
        finite cost exists; the tour is then arbitrary).
    """
    A = np.asarray(A, dtype=np.float64)
    m = A.shape[0]
    if m > MAX_NODES:
        raise ValueError(
            f"Held-Karp on {m} nodes needs {8 * (m - 1) * 2 ** (m - 1) / 1e9:.1f} GB; "
            f"the limit is {MAX_NODES} nodes (use method='pso')"
        )
    if m == 1:
        return np.array([start], dtype=np.intp), 0.0
    others = np.array([v for v in range(m) if v != start], dtype=np.intp)
    k = m - 1
    B = A[np.ix_(others, others)]  # (k, k) costs among the other nodes
    from_start = A[start, others]
    to_start = A[others, start]
    D = np.full((1 << k, k), np.inf)
    bits = 1 << np.arange(k, dtype=np.int64)
    D[bits, np.arange(k)] = from_start
    levels = _levels(k)
    for c in range(2, k + 1):
        S = levels[c]
        for j in range(k):
            Sj = S[(S & bits[j]) != 0]
            prev = D[Sj ^ bits[j]]  # (len(Sj), k); inf where i not in the subset
            D[Sj, j] = np.min(prev + B[:, j], axis=1)
    full = (1 << k) - 1
    total = D[full] + to_start
    j = int(np.argmin(total))
    best = float(total[j])
    if not np.isfinite(best):
        return np.concatenate([[start], others]).astype(np.intp), best
    # Backtrack: the same expressions, so argmin finds the stored minimum exactly.
    path = [j]
    S = full
    while S != bits[j]:
        S_prev = S ^ int(bits[j])
        i = int(np.argmin(D[S_prev] + B[:, j]))
        path.append(i)
        S, j = S_prev, i
    path.reverse()
    tour = np.concatenate([[start], others[np.asarray(path, dtype=np.intp)]]).astype(np.intp)
    log.debug("Held-Karp on %d nodes: cost %.6g", m, best)
    return tour, best
