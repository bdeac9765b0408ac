"""Cost matrices for sequencing, and the reduction of every sequencing variant to one closed tour.

The sequencer works on any ``(n, n)`` cost matrix: straight-line distances by default, the local
planner's collision-free path lengths in the weld pipeline, travel times elsewhere. Entries may be
asymmetric and may be ``inf`` (an unreachable pair); the diagonal is ignored.

Every variant a weld station needs (open path with free ends, closed tour, fixed first joint,
fixed last joint) is reduced here to *a closed tour over a matrix* ``A`` *that starts at node*
``start``, so the exact solver, the swarm, the nearest-neighbour construction and the local search
each solve only that one problem:

* open path: a dummy node ``n`` is appended with zero cost to and from every joint; the tour is cut
  at the dummy. A fixed first joint ``f`` leaves only ``dummy -> f`` finite, a fixed last joint
  ``l`` only ``l -> dummy``.
* closed tour: ``A = cost`` and ``start`` is the first joint (node 0 when none is fixed, since a
  closed tour has no start); a fixed last joint ``l`` alone rotates the result so ``l`` comes last;
  both fixed force the edge ``l -> f`` by making every other edge out of ``l`` infinite.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: ``cost(points_a (k, d), points_b (k, d)) -> (k,)``: the cost of going from each a to each b.
PairCost = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def euclidean(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Straight-line distance between rows of ``a (k, d)`` and ``b (k, d)``: ``(k,)``."""
    return np.sqrt(np.sum((np.asarray(b) - np.asarray(a)) ** 2, axis=-1))


def cost_matrix(points: ArrayLike, cost: PairCost = euclidean) -> NDArray[np.float64]:
    """The ``(n, n) float`` matrix ``C[i, j] = cost(points[i], points[j])`` (diagonal 0).

    Parameters
    ----------
    points
        ``(n, d) float``: joint positions (mm in 3D) or any per-node data ``cost`` understands.
    cost
        Vectorised pair cost (see :data:`PairCost`); straight-line distance by default. It may
        return ``inf`` for an unreachable pair and need not be symmetric.
    """
    P = np.asarray(points, dtype=np.float64)
    if P.ndim != 2:
        raise ValueError(f"points must be (n, d), got shape {P.shape}")
    n = P.shape[0]
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    C = np.asarray(cost(P[i.ravel()], P[j.ravel()]), dtype=np.float64).reshape(n, n)
    np.fill_diagonal(C, 0.0)
    return C


def check_cost(cost: ArrayLike) -> NDArray[np.float64]:
    """Validate a cost matrix: square, float, no NaN, no ``-inf``. Returns a float64 copy."""
    C = np.array(cost, dtype=np.float64)
    if C.ndim != 2 or C.shape[0] != C.shape[1]:
        raise ValueError(f"cost matrix must be square (n, n), got shape {C.shape}")
    if C.shape[0] == 0:
        raise ValueError("cost matrix is empty: nothing to sequence")
    if np.isnan(C).any():
        i, j = np.argwhere(np.isnan(C))[0]
        raise ValueError(f"cost matrix has NaN at [{i}, {j}]; use inf for an unreachable pair")
    if np.isneginf(C).any():
        i, j = np.argwhere(np.isneginf(C))[0]
        raise ValueError(f"cost matrix has -inf at [{i}, {j}]")
    np.fill_diagonal(C, 0.0)
    return C


def order_cost(cost: NDArray[np.float64], order: ArrayLike, closed: bool) -> float:
    """Cost of visiting ``order`` (``(n,) int``); ``closed`` adds the edge back to the start."""
    o = np.asarray(order, dtype=np.intp)
    c = float(cost[o[:-1], o[1:]].sum()) if len(o) > 1 else 0.0
    if closed and len(o) > 1:
        c += float(cost[o[-1], o[0]])
    return c


def penalised(A: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
    """``A`` with ``inf`` replaced by a finite penalty ``big`` larger than any finite tour.

    Heuristics compare tours by sums, which ``inf`` would flatten (every tour through one
    unreachable pair would tie with every other). With ``big > 2 m max|A|`` a tour with ``k``
    unreachable pairs always costs more than any tour with ``k - 1``, so the heuristics avoid them
    and still rank infeasible tours by how infeasible they are.
    """
    finite = np.isfinite(A)
    scale = float(np.abs(A[finite]).max()) if finite.any() else 1.0
    big = 4.0 * A.shape[0] * max(scale, 1.0) + 1.0
    return np.where(finite, A, big), big


@dataclass(frozen=True)
class Reduction:
    """A sequencing variant as a closed tour over ``A`` starting at ``start``.

    Attributes
    ----------
    A
        ``(m, m) float``: tour costs, ``inf`` where an edge is unreachable or forbidden.
    start
        The node every tour starts at (the dummy for open paths).
    n
        Number of real nodes.
    closed, first, last
        The variant.
    """

    A: NDArray[np.float64]
    start: int
    n: int
    closed: bool
    first: int | None
    last: int | None

    @property
    def m(self) -> int:
        return int(self.A.shape[0])

    def to_order(self, tour: ArrayLike) -> NDArray[np.intp]:
        """Map a closed tour over ``A`` (any rotation) back to the visiting order of real nodes."""
        t = np.asarray(tour, dtype=np.intp)
        k = int(np.flatnonzero(t == self.start)[0])
        t = np.roll(t, -k)
        if not self.closed:
            return t[1:].copy()
        if self.last is not None and self.first is None:
            k = int(np.flatnonzero(t == self.last)[0])
            t = np.roll(t, -(k + 1))
        return t.copy()

    def to_tour(self, order: ArrayLike) -> NDArray[np.intp]:
        """The closed tour over ``A`` (starting at ``start``) that visits ``order``."""
        o = np.asarray(order, dtype=np.intp)
        if not self.closed:
            return np.concatenate([[self.start], o]).astype(np.intp)
        k = int(np.flatnonzero(o == self.start)[0])
        return np.roll(o, -k)


def reduce_to_tour(
    cost: NDArray[np.float64], closed: bool, first: int | None, last: int | None
) -> Reduction:
    """Build the :class:`Reduction` of a validated ``cost`` matrix (see the module docstring)."""
    n = cost.shape[0]
    for name, v in (("first", first), ("last", last)):
        if v is not None and not (0 <= v < n):
            raise ValueError(f"{name}={v} is not a node index in 0..{n - 1}")
    if first is not None and last is not None and first == last and n > 1:
        raise ValueError(f"first and last are the same node ({first}) of {n}")
    if closed:
        A = cost.copy()
        if first is not None and last is not None:
            keep = A[last, first]
            A[last, :] = np.inf
            A[last, first] = keep
            A[last, last] = 0.0
        start = first if first is not None else (last if last is not None else 0)
        return Reduction(A, int(start), n, True, first, last)
    A = np.zeros((n + 1, n + 1))
    A[:n, :n] = cost
    if first is not None:
        A[n, :n] = np.inf
        A[n, first] = 0.0
    if last is not None:
        A[:n, n] = np.inf
        A[last, n] = 0.0
    A[n, n] = 0.0
    return Reduction(A, n, n, False, first, last)
