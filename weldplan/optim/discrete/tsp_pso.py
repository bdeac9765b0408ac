"""Discrete particle swarm for tours, after Clerc (2004), as used by Wang et al. (2017), section 5.

Clerc, M. (2004), "Discrete particle swarm optimization, illustrated by the traveling salesman
problem", in *New Optimization Techniques in Engineering*, Springer, pp. 219-239. Wang, Xue, Yan
and Gu (2017), "Welding robot collision-free path optimization", Applied Sciences 7(2) 89,
section 5.2, use it with the parameters of their Table 4 (the defaults of :class:`PSOParams`).

A *position* is a permutation (the visiting order), a *velocity* an ordered list of
transpositions. Clerc's algebra:

* ``x + v``: apply the transpositions of ``v`` to ``x`` in order;
* ``x - y``: the velocity ``v`` with ``y + v = x`` (built greedily position by position, so it has
  at most ``n - 1`` transpositions);
* ``c * v`` for ``c >= 0``: ``floor(c)`` copies of ``v`` followed by the first
  ``floor(frac(c) |v|)`` transpositions of ``v`` (truncation when ``c < 1``);
* ``v + w``: concatenation.

The update is Eqs. (6)-(7) of the paper with these operators:

    v <- w * v  +  c1 r1 * (pbest - x)  +  c2 r2 * (gbest - x),      x <- x + v

with ``r1, r2 ~ U[0, 1]`` drawn per particle and iteration.

Implementation: the swarm is arrays (positions ``(k, P) int``, velocities as two ``(L, P) int``
arrays of transposition ends padded with no-op swaps ``(0, 0)``, lengths ``(P,)``); every operator
loops over list positions with the whole swarm at once (``pbest - x`` and ``gbest - x`` share one
sweep), and tour costs of the swarm are one gather-and-sum. Deviation (named): Clerc's refinements
beyond the basic update (NoHope/ReHope restarts, velocity reduction) are not used, as the paper
lists none. Safeguard (named): when a velocity grows longer than ``MAX_VELOCITY (n - 1)``
transpositions it is replaced by the equivalent minimal one ``(x + v) - x`` (same move, shorter
list), which bounds memory and time per iteration for large coefficients; with Table 4's
parameters ``|v| <= 0.4 |v| + 2 (n - 1)`` stays below ``3.34 (n - 1)`` and it never fires.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

log = logging.getLogger(__name__)

#: Velocities longer than ``MAX_VELOCITY (n - 1)`` transpositions are contracted (see above).
#: With Table 4's coefficients ``|v'| <= 0.4 |v| + 2 (n - 1)``, so ``|v|`` stays below
#: ``2 (n - 1) / 0.6 < 3.4 (n - 1)`` and the contraction never fires with the paper's parameters.
MAX_VELOCITY = 4


@dataclass(frozen=True)
class PSOParams:
    """Settings of the discrete swarm; defaults are Table 4 of Wang et al. (2017).

    Attributes
    ----------
    iterations
        Swarm iterations ``N`` (Table 4: 100).
    particles
        Population size (Table 4: 50).
    c1, c2
        Learning rates towards the personal and global best (Table 4: 1.0, 1.0).
    weight
        Inertia weight ``w`` on the previous velocity (Table 4: 0.4).
    """

    iterations: int = 100
    particles: int = 50
    c1: float = 1.0
    c2: float = 1.0
    weight: float = 0.4

    def __post_init__(self) -> None:
        if self.iterations < 0 or self.particles < 1:
            raise ValueError("PSOParams needs iterations >= 0 and particles >= 1")
        if min(self.c1, self.c2, self.weight) < 0:
            raise ValueError("PSOParams coefficients c1, c2, weight must be >= 0")

    def to_dict(self) -> dict[str, float | int]:
        return asdict(self)


@dataclass
class Velocity:
    """Transposition lists of the whole swarm: particle ``p`` swaps positions ``a[t, p]`` and
    ``b[t, p]`` for ``t = 0, 1, ...``.

    ``a``, ``b`` are ``(L, P) int`` (list position first, so each step is a contiguous row);
    entries at ``t >= length[p]`` are the no-op ``(0, 0)``.
    """

    a: NDArray[np.intp]
    b: NDArray[np.intp]
    length: NDArray[np.intp]


# Layout: positions are stored transposed, ``X[q, p]`` = node at position ``q`` of particle
# ``p`` (``(k, P)``), so the operators' loops over list positions touch contiguous rows and use
# flat 1-D gathers (measured 2-3x faster than row-major 2-D fancy indexing for P = 50).


def tour_costs(
    A: NDArray[np.float64], start: int, X: NDArray[np.intp], others: NDArray[np.intp]
) -> NDArray[np.float64]:
    """Costs ``(P,)`` of the closed tours ``start -> others[X[:, p]] -> start`` over ``A``."""
    nodes = others[X]
    c = A[start, nodes[0]] + A[nodes[-1], start]
    if nodes.shape[0] > 1:
        c = c + A[nodes[:-1], nodes[1:]].sum(axis=0)
    return c


def apply_velocity(X: NDArray[np.intp], v: Velocity) -> NDArray[np.intp]:
    """``x + v`` for every particle: a new ``(k, P)`` array of positions."""
    k, P = X.shape
    flat = X.ravel().copy()
    rows = np.arange(P)
    n_steps = int(v.length.max(initial=0))
    ia = v.a[:n_steps] * P + rows
    ib = v.b[:n_steps] * P + rows
    for t in range(n_steps):
        xa = flat[ia[t]]
        flat[ia[t]] = flat[ib[t]]
        flat[ib[t]] = xa
    return flat.reshape(k, P)


def difference(X: NDArray[np.intp], Y: NDArray[np.intp]) -> Velocity:
    """``x - y`` for every particle: transpositions that turn ``Y[:, p]`` into ``X[:, p]``.

    Clerc's construction: for each position ``q`` in turn, swap into it the node ``x`` has
    there; a swap is recorded only when the node was elsewhere.
    """
    k, P = X.shape
    rows = np.arange(P)
    # Work on flat keys: node v of particle p is ``v * P + p``, position q of particle p is
    # ``q * P + p``; then each step is gathers and scatters with no index arithmetic.
    XP = X * P + rows
    y = (Y * P + rows).ravel()  # y[q * P + p] = key of the node at position q
    pos = np.empty(k * P, dtype=np.intp)  # pos[key] = flat position of that node
    pos[y] = np.arange(k * P)
    QP = np.arange(k * P).reshape(k, P)
    bf = QP.copy()  # (q, q): no-op
    for q in range(k - 1):
        w = XP[q]
        jf = pos[w]
        bf[q] = jf
        lo, hi = q * P, (q + 1) * P
        yq = y[lo:hi].copy()
        y[jf] = yq
        y[lo:hi] = w
        pos[yq] = jf
        pos[w] = QP[q]
    b = bf // P
    # compact each column's real transpositions (q != b[q]) to the front, keeping their order
    real = b != np.arange(k)[:, None]
    qi, col = np.nonzero(real)
    dest = (np.cumsum(real, axis=0) - 1)[qi, col]
    a_out = np.zeros((k, P), dtype=np.intp)
    b_out = np.zeros((k, P), dtype=np.intp)
    a_out[dest, col] = qi
    b_out[dest, col] = b[qi, col]
    return Velocity(a_out, b_out, real.sum(axis=0))


def scale(c: NDArray[np.float64], v: Velocity) -> Velocity:
    """``c * v`` for every particle (``c (P,) >= 0``): ``floor(c)`` copies of ``v``, then the
    first ``floor(frac(c) |v|)`` transpositions (so truncation when ``c < 1``)."""
    new_len = np.floor(c * v.length).astype(np.intp)
    L = int(new_len.max(initial=0))
    P = v.length.shape[0]
    if L == 0:
        return Velocity(np.zeros((1, P), np.intp), np.zeros((1, P), np.intp), new_len)
    t = np.arange(L)[:, None]
    if L <= v.a.shape[0] and np.all(new_len <= v.length):  # c <= 1: a plain truncation
        a, b = v.a[:L].copy(), v.b[:L].copy()
    else:
        src = np.minimum(t % np.maximum(v.length, 1)[None, :], v.a.shape[0] - 1)
        a = np.take_along_axis(v.a, src, axis=0)
        b = np.take_along_axis(v.b, src, axis=0)
    pad = t >= new_len[None, :]
    a[pad] = 0
    b[pad] = 0
    return Velocity(a, b, new_len)


def concat(v: Velocity, w: Velocity) -> Velocity:
    """``v + w`` for every particle: ``w``'s transpositions after ``v``'s."""
    P = v.length.shape[0]
    length = v.length + w.length
    L = max(int(length.max(initial=0)), 1)
    a = np.zeros((L, P), np.intp)
    b = np.zeros((L, P), np.intp)
    Lv = min(v.a.shape[0], L)
    a[:Lv] = v.a[:Lv]
    b[:Lv] = v.b[:Lv]
    keep = np.arange(w.a.shape[0])[:, None] < w.length[None, :]
    q, r = np.nonzero(keep)
    dest = v.length[r] + q
    a[dest, r] = w.a[q, r]
    b[dest, r] = w.b[q, r]
    return Velocity(a, b, length)


def random_velocity(P: int, k: int, rng: np.random.Generator) -> Velocity:
    """Random initial velocities: ``U{0..k-1}`` random transpositions per particle."""
    length = rng.integers(0, max(k, 1), size=P)
    L = max(int(length.max(initial=0)), 1)
    a = rng.integers(0, k, size=(L, P))
    b = rng.integers(0, k, size=(L, P))
    pad = np.arange(L)[:, None] >= length[None, :]
    a[pad] = 0
    b[pad] = 0
    return Velocity(a.astype(np.intp), b.astype(np.intp), length.astype(np.intp))


@dataclass(frozen=True)
class SwarmResult:
    """What one run of :func:`tsp_pso` found (internal; :class:`Sequence` is the public result).

    ``tour`` is ``(m,) int`` starting at ``start``; ``history`` the best cost after
    initialisation and after each iteration.
    """

    tour: NDArray[np.intp]
    cost: float
    history: tuple[float, ...]
    evaluations: int
    iterations: int


def tsp_pso(
    A: NDArray[np.float64],
    start: int,
    params: PSOParams,
    rng: np.random.Generator,
    callback: Callable[[int, float], bool | None] | None = None,
) -> SwarmResult:
    """Clerc's discrete PSO for the closed tour over ``A`` that starts at ``start``.

    Parameters
    ----------
    A
        ``(m, m) float``, finite (replace ``inf`` by a penalty first, see
        :func:`~weldplan.optim.discrete.costs.penalised`).
    start
        The fixed first node; particles permute the other ``m - 1``.
    params
        Swarm settings (paper defaults).
    rng
        The generator every random draw comes from.
    callback
        ``callback(iteration, best_cost)`` after initialisation (iteration 0) and after every
        iteration; returning ``True`` stops the swarm.
    """
    m = A.shape[0]
    others = np.array([v for v in range(m) if v != start], dtype=np.intp)
    k = m - 1
    P = params.particles
    if k <= 1:
        tour = np.concatenate([[start], others]).astype(np.intp)
        c = float(tour_costs(A, start, np.zeros((k, 1), np.intp), others)[0]) if k else 0.0
        return SwarmResult(tour, c, (c,), 1, 0)
    X = np.argsort(rng.random((k, P)), axis=0).astype(np.intp)
    V = random_velocity(P, k, rng)
    F = tour_costs(A, start, X, others)
    evals = P
    pbest, pbest_f = X.copy(), F.copy()
    g = int(np.argmin(F))
    gbest, gbest_f = X[:, g].copy(), float(F[g])
    history = [gbest_f]
    done = 0
    if callback is not None and callback(0, gbest_f):
        params = PSOParams(0, P, params.c1, params.c2, params.weight)
    for it in range(1, params.iterations + 1):
        r1 = rng.random(P)
        r2 = rng.random(P)
        inertia = scale(np.full(P, params.weight), V)
        # pbest - x and gbest - x in one sweep over positions (2P columns: half the loop cost)
        both = difference(
            np.concatenate([pbest, np.broadcast_to(gbest[:, None], X.shape)], axis=1),
            np.concatenate([X, X], axis=1),
        )
        coeff = np.concatenate([params.c1 * r1, params.c2 * r2])
        moves = scale(coeff, both)
        cognitive = Velocity(moves.a[:, :P], moves.b[:, :P], moves.length[:P])
        social = Velocity(moves.a[:, P:], moves.b[:, P:], moves.length[P:])
        V = concat(concat(inertia, cognitive), social)
        Xn = apply_velocity(X, V)
        if int(V.length.max(initial=0)) > MAX_VELOCITY * (k - 1):
            V = difference(Xn, X)  # equivalent minimal velocity (named deviation)
        X = Xn
        F = tour_costs(A, start, X, others)
        evals += P
        better = F < pbest_f
        pbest[:, better] = X[:, better]
        pbest_f[better] = F[better]
        g = int(np.argmin(pbest_f))
        if pbest_f[g] < gbest_f:
            gbest, gbest_f = pbest[:, g].copy(), float(pbest_f[g])
        history.append(gbest_f)
        done = it
        if callback is not None and callback(it, gbest_f):
            break
    tour = np.concatenate([[start], others[gbest]]).astype(np.intp)
    log.debug("TSP-PSO: %d iterations, %d evaluations, best %.6g", done, evals, gbest_f)
    return SwarmResult(tour, gbest_f, tuple(history), evals, done)
