"""Lower bounds on the shortest tour or open path over a cost matrix.

The Held-Karp 1-tree bound (Held & Karp, *Operations Research* 18, 1970, and *Mathematical
Programming* 1, 1971): for node penalties ``pi``, every tour is a 1-tree (a spanning tree of the
nodes other than a special one, plus two edges at the special node) in which every node has
degree 2, so

    w(pi) = min over 1-trees T of sum_{(i,j) in T} (c_ij + pi_i + pi_j) - 2 sum_i pi_i

is a lower bound on the shortest tour for every ``pi``. Subgradient ascent on ``pi``
(``g_i = deg_T(i) - 2``, Polyak steps towards an upper bound) raises it; on Euclidean instances
it typically ends within 1-2 % of the optimum, where the minimum spanning tree alone is 10-30 %
below. An open path with free ends is a tour through one extra node joined to every node at cost
0, which is how ``open_path=True`` works.

Used beside every sequence too large for the exact Held-Karp dynamic programme, so a route's
gap is measured against a bound that means something.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True)
class OneTreeBound:
    """The outcome of :func:`one_tree`.

    Attributes
    ----------
    bound
        The best bound seen (a valid lower bound however the ascent stopped).
    iterations
        Subgradient iterations run (each one minimum spanning tree).
    clock_stopped
        The CPU-time cap stopped the ascent before its work bounds (``max_iter``, the step
        size) did: the bound then depends on the machine's speed and load.
    """

    bound: float
    iterations: int
    clock_stopped: bool


def one_tree_bound(
    cost: ArrayLike,
    *,
    open_path: bool = True,
    upper: float | None = None,
    max_iter: int = 300,
    max_seconds: float | None = None,
    tol: float = 1e-6,
) -> float:
    """Held-Karp 1-tree lower bound on the shortest tour (or open path) over ``cost``: the
    ``bound`` of :func:`one_tree` (same parameters)."""
    return one_tree(
        cost, open_path=open_path, upper=upper, max_iter=max_iter, max_seconds=max_seconds,
        tol=tol,
    ).bound  # fmt: skip


def one_tree(
    cost: ArrayLike,
    *,
    open_path: bool = True,
    upper: float | None = None,
    max_iter: int = 300,
    max_seconds: float | None = None,
    tol: float = 1e-6,
) -> OneTreeBound:
    """Held-Karp 1-tree lower bound on the shortest tour (or open path) over ``cost``.

    Parameters
    ----------
    cost
        ``(n, n)`` symmetric non-negative costs (the diagonal is ignored).
    open_path
        Bound the shortest Hamiltonian path with free ends (weldplan's routes) instead of the
        shortest closed tour.
    upper
        A known tour / path length (any feasible one), used for the Polyak step size; default:
        the nearest-neighbour tour's length.
    max_iter
        Subgradient iterations (each one minimum spanning tree of ``n`` nodes: about 0.1 s
        at 1,000 nodes).
    max_seconds
        Stop after this many CPU seconds of the calling thread (``time.thread_time``; the
        bound so far stays valid). CPU, not wall, time: on a shared machine a wall cap let the
        4000-joint station's bound run a handful of steps, so the same route got a looser bound
        the busier the machine was.
    tol
        Stop when the step size falls below ``tol`` times the bound, or a 1-tree is a tour.

    Returns
    -------
    OneTreeBound
        The best bound seen (a valid lower bound whatever ``max_iter`` is), the iterations
        run and whether the CPU-time cap stopped them.
    """
    C = np.array(cost, dtype=np.float64)
    n0 = len(C)
    if C.shape != (n0, n0):
        raise ValueError(f"cost must be square, got shape {C.shape}")
    if n0 < 2:
        return OneTreeBound(0.0, 0, False)
    if open_path:
        C = np.pad(C, ((0, 1), (0, 1)))  # node n0 joined to every node at cost 0
    C = 0.5 * (C + C.T)
    n = len(C)
    if n < 3:  # a closed tour of two nodes: there and back
        return OneTreeBound(2.0 * float(C[0, 1]), 0, False)
    if upper is None:
        upper = _nearest_neighbour_tour(C)
    special = n - 1  # the dummy node of an open path, else any node
    rest = np.arange(n - 1)
    pi = np.zeros(n)
    best = -np.inf
    lam, stall = 2.0, 0
    t_end = None if max_seconds is None else time.thread_time() + max_seconds
    it, clock = 0, False
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        if t_end is not None and time.thread_time() > t_end and np.isfinite(best):
            it, clock = it - 1, True
            break
        W = C + pi[:, None] + pi[None, :]
        w, parent = dense_mst(W[: n - 1, : n - 1])
        near = np.argsort(W[special, rest])[:2]
        w += float(W[special, rest[near]].sum())
        bound = w - 2.0 * float(pi.sum())
        deg = np.zeros(n)
        np.add.at(deg, parent[1:], 1)
        deg[1 : n - 1] += 1
        deg[rest[near]] += 1
        deg[special] = 2
        if bound > best + tol * abs(best if np.isfinite(best) else 1.0):
            best, stall = bound, 0
        else:
            stall += 1
            if stall >= 10:
                lam, stall = lam / 2.0, 0
        g = deg - 2.0
        gg = float(g @ g)
        if gg == 0.0:  # the 1-tree is a tour: the bound is the optimum
            break
        step = lam * max(upper - bound, tol * abs(bound)) / gg
        if step < tol * max(abs(best), 1.0) / n:
            break
        pi += step * g
    return OneTreeBound(float(best), it, clock)


def dense_mst(W: NDArray[np.float64]) -> tuple[float, NDArray[np.intp]]:
    """Minimum spanning tree of the complete graph ``W (k, k)`` (symmetric) by Prim's O(k^2)
    algorithm, one vectorised row update per added node.

    Returns the tree's weight and ``parent (k,)`` (``parent[0] = -1``; node ``v > 0`` hangs from
    ``parent[v]``). On dense matrices it is ~10x faster than scipy's sparse
    ``minimum_spanning_tree`` (measured at 1,001 nodes: 0.21 s against 2.2 s at load 8 on 2
    cores), which is what the subgradient ascent repeats hundreds of times.
    """
    k = W.shape[0]
    parent = np.full(k, -1, dtype=np.intp)
    if k < 2:
        return 0.0, parent
    in_tree = np.zeros(k, dtype=bool)
    in_tree[0] = True
    d = W[0].astype(np.float64, copy=True)
    d[0] = np.inf
    parent[1:] = 0
    total = 0.0
    for _ in range(k - 1):
        j = int(np.argmin(d))
        total += float(d[j])
        in_tree[j] = True
        d[j] = np.inf
        row = W[j]
        better = (row < d) & ~in_tree
        d[better] = row[better]
        parent[better] = j
    return total, parent


def _nearest_neighbour_tour(C: NDArray[np.float64]) -> float:
    n = len(C)
    seen = np.zeros(n, dtype=bool)
    i, total = 0, 0.0
    seen[0] = True
    for _ in range(n - 1):
        d = np.where(seen, np.inf, C[i])
        j = int(np.argmin(d))
        total += float(d[j])
        seen[j] = True
        i = j
    return total + float(C[i, 0])
