"""Artificial bee colony (ABC) and its multi-swarm variant (MABC): the bee baselines of 003.

ABC: Karaboga & Basturk, J. Global Optim. 39:459-471, 2007, as restated in 003 section 2.1
(``../shared/papers/003_*``): employed bees (eq. 1), onlookers choosing food sources by roulette
(eq. 2), scouts re-sampling abandoned sources (eq. 3).

Named deviations (vectorisation)
--------------------------------
* Karaboga's employed and onlooker phases visit the sources one after another, so a bee may copy
  a neighbour that was improved a moment earlier. Here every bee of a phase searches from the
  colony as it was at the start of the phase (one batch, one ``ctx.evaluate``, over all the
  sub-colonies of MABC at once). When several
  onlookers land on one source the best candidate competes with it (greedy); a source that no
  onlooker improves has its trial counter raised once per unsuccessful onlooker.
* Candidates leaving the box are clipped to it.
"""

from __future__ import annotations

import logging

import numpy as np
from numpy.typing import NDArray

from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds

log = logging.getLogger(__name__)

#: 003 section 5.2: "the look limitation is adapted as 5 x NP" for ABC and MABC.
LIMIT_FACTOR = 5


def abc_fitness(F: NDArray[np.float64]) -> NDArray[np.float64]:
    """Karaboga's fitness of objective values ``F (n,)``: ``1 / (1 + f)`` for ``f >= 0``, else
    ``1 + |f|``; non-negative, larger is better (the ``fit_i`` of 003 eq. 2)."""
    F = np.asarray(F, dtype=np.float64)
    out = np.where(F >= 0, 1.0 / (1.0 + np.abs(F)), 1.0 + np.abs(F))
    return np.where(np.isfinite(F), out, 0.0)


def roulette_rows(
    rng: np.random.Generator, weights: NDArray[np.float64], size: int
) -> NDArray[np.intp]:
    """Roulette draws within each row: ``weights (S, n)`` -> ``(S, size)`` column indices.

    Row ``s`` draws with probability proportional to ``weights[s]`` (non-finite counts as 0; a
    row of zeros draws uniformly), all rows in one ``searchsorted`` (the colonies of MABC and
    the swarms of ParaPA choose at once).
    """
    W = np.where(np.isfinite(weights), weights, 0.0)
    S, n = W.shape
    total = W.sum(axis=1, keepdims=True)
    W = np.where(total > 0, W, 1.0)
    cdf = np.cumsum(W, axis=1)
    cdf /= cdf[:, -1:]
    offs = np.arange(S, dtype=np.float64)[:, None]
    r = rng.random((S, size)) + offs
    idx = np.searchsorted((cdf + offs).ravel(), r.ravel(), side="right").reshape(S, size)
    return np.clip(idx - np.arange(S)[:, None] * n, 0, n - 1)


def neighbour_search(
    rng: np.random.Generator, X: NDArray[np.float64], rows: NDArray[np.intp]
) -> NDArray[np.float64]:
    """Eq. 1: ``v_ij = x_ij + phi (x_ij - x_kj)``, one random ``j``, partner ``k != i``.

    Parameters
    ----------
    X
        ``(S, n, n_var)``: ``S`` colonies of ``n`` food sources; partners come from the bee's
        own colony.
    rows
        ``(S, m)`` index (within its colony) of the source each bee exploits.

    Returns
    -------
    ``(S, m, n_var)`` candidates (not clipped)
    """
    S, n, n_var = X.shape
    m = rows.shape[1]
    sidx = np.arange(S)[:, None]
    if n > 1:
        k = rng.integers(0, n - 1, (S, m))
        k = k + (k >= rows)  # uniform over the sources other than the bee's own
    else:
        k = np.zeros((S, m), dtype=np.intp)
    j = rng.integers(0, n_var, (S, m))
    phi = rng.uniform(-1.0, 1.0, (S, m))
    V = X[sidx, rows]
    b = np.arange(m)[None, :]
    xj = V[sidx, b, j]
    V[sidx, b, j] = xj + phi * (xj - X[sidx, k, j])
    return V


class ABC(Optimizer):
    """Artificial bee colony (Karaboga 2007; 003 eq. 1-3).

    Parameters
    ----------
    pop_size
        Colony size ``NP``: ``NP // 2`` food sources, as many employed bees and as many onlookers
        (003 section 5.2: "the size of onlookers is equal to the size of employed bees"; NP = 50).
    limit
        Trials before a source is abandoned to a scout; ``None`` gives ``5 * NP`` (003 section
        5.2; Karaboga uses ``SN * D``).

    Notes
    -----
    One iteration evaluates ``NP // 2`` employed candidates, ``NP // 2`` onlooker candidates and
    at most one scout (Karaboga: one scout per cycle).
    """

    name = "abc"

    def __init__(self, pop_size: int = 50, limit: int | None = None) -> None:
        super().__init__(pop_size)
        if pop_size < 2:
            raise ValueError("ABC needs pop_size >= 2 (employed bees and onlookers)")
        self.limit = limit

    @property
    def n_sources(self) -> int:
        return max(self.pop_size // 2, 1)

    def _limit(self) -> int:
        return self.limit if self.limit is not None else LIMIT_FACTOR * self.pop_size

    def initialize(self, ctx: Context) -> None:
        self.X = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.n_sources)
        self.F = ctx.evaluate(self.X)
        self.trial = np.zeros(self.n_sources, dtype=np.int64)

    def step(self, ctx: Context) -> None:
        abc_cycle(ctx, self.X[None], self.F[None], self.trial[None], self._limit())


def abc_cycle(
    ctx: Context,
    X: NDArray[np.float64],
    F: NDArray[np.float64],
    trial: NDArray[np.int64],
    limit: int,
) -> None:
    """One ABC cycle on ``S`` colonies at once, updated in place.

    ``X (S, n, n_var)``, ``F (S, n)``, ``trial (S, n)``; bees search within their own colony.
    Each phase is one ``ctx.evaluate`` over all colonies.
    """
    rng = ctx.rng
    S, n, D = X.shape
    lo, hi = ctx.lower, ctx.upper
    sidx = np.arange(S)[:, None]
    # Employed bees (eq. 1) with greedy selection.
    rows = np.broadcast_to(np.arange(n), (S, n))
    V = clip_to_bounds(neighbour_search(rng, X, rows), lo, hi)
    Fv = ctx.evaluate(V.reshape(-1, D)).reshape(S, n)
    better = Fv < F
    X[better] = V[better]
    F[better] = Fv[better]
    trial[better] = 0
    trial[~better] += 1
    # Onlookers: sources by roulette on fitness (eq. 2), then eq. 1 from the chosen source.
    chosen = roulette_rows(rng, abc_fitness(F), n)
    V = clip_to_bounds(neighbour_search(rng, X, chosen), lo, hi).reshape(-1, D)
    Fv = ctx.evaluate(V).reshape(-1)
    key = (sidx * n + chosen).reshape(-1)  # global source index of every onlooker
    order = np.lexsort((Fv, key))  # by source, best candidate first
    first = np.ones(key.size, dtype=bool)
    first[1:] = key[order][1:] != key[order][:-1]
    best_c = order[first]  # best candidate of each chosen source
    src = key[best_c]
    Xf, Ff, Tf = X.reshape(-1, D), F.reshape(-1), trial.reshape(-1)
    imp = Fv[best_c] < Ff[src]
    Xf[src[imp]] = V[best_c[imp]]
    Ff[src[imp]] = Fv[best_c[imp]]
    visits = np.bincount(key, minlength=S * n)
    not_improved = np.ones(S * n, dtype=bool)
    not_improved[src[imp]] = False
    Tf[src[imp]] = 0
    Tf[not_improved] += visits[not_improved]
    X[:], F[:], trial[:] = Xf.reshape(S, n, D), Ff.reshape(S, n), Tf.reshape(S, n)
    # Scouts (eq. 3): the most exhausted source of each colony, if past the limit, is re-sampled.
    worn = np.argmax(trial, axis=1)
    cols = np.flatnonzero(trial[np.arange(S), worn] > limit)
    if cols.size and not ctx.exhausted():
        X[cols, worn[cols]] = random_in_bounds(rng, lo, hi, cols.size)
        F[cols, worn[cols]] = ctx.evaluate(X[cols, worn[cols]])
        trial[cols, worn[cols]] = 0


class MABC(Optimizer):
    """Multi-swarm ABC: ``n_swarms`` independent colonies with ring migration of their bests.

    003 uses MABC as a baseline without defining it; this is the usual island model: the colony
    of ``pop_size`` bees is split into ``n_swarms`` sub-colonies that run :class:`ABC` cycles
    side by side, and every ``migration_interval`` iterations the best source of each
    sub-colony replaces the worst source of the next one (ring), its trial counter reset.

    Parameters
    ----------
    pop_size
        Total colony size over all sub-colonies (default 3 x 50: 003's NP = 50 per swarm).
    n_swarms
        Number of sub-colonies (003 does not state it; 3 is our default). A colony too small for
        that many (two bees each) is split into ``pop_size // 2``.
    limit
        Abandonment limit per sub-colony; ``None`` gives ``5 * NP_swarm`` (003 section 5.2).
    migration_interval
        Iterations between migrations (our default: 10).
    """

    name = "mabc"

    def __init__(
        self,
        pop_size: int = 150,
        n_swarms: int = 3,
        limit: int | None = None,
        migration_interval: int = 10,
    ) -> None:
        super().__init__(pop_size)
        if n_swarms < 1 or pop_size < 2:
            raise ValueError(f"need pop_size >= 2 and n_swarms >= 1, got {pop_size}, {n_swarms}")
        if migration_interval < 1:
            raise ValueError("migration_interval must be >= 1")
        self.n_swarms = int(n_swarms)
        self.limit = limit
        self.migration_interval = int(migration_interval)

    def initialize(self, ctx: Context) -> None:
        # a sub-colony needs two bees (one source); fewer colonies when the colony is small
        self._ns = min(self.n_swarms, self.pop_size // 2)
        if self._ns < self.n_swarms:
            log.info(
                "MABC: %d bees make %d sub-colonies, not %d", self.pop_size, self._ns, self.n_swarms
            )
        np_swarm = self.pop_size // self._ns
        self._sn = max(np_swarm // 2, 1)
        self._lim = self.limit if self.limit is not None else LIMIT_FACTOR * np_swarm
        ns = self._ns
        X = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, ns * self._sn)
        F = ctx.evaluate(X)
        self.X = X.reshape(ns, self._sn, -1)
        self.F = F.reshape(ns, self._sn)
        self.trial = np.zeros((ns, self._sn), dtype=np.int64)

    def step(self, ctx: Context) -> None:
        ns = self._ns
        abc_cycle(ctx, self.X, self.F, self.trial, self._lim)
        if ns > 1 and (ctx.iteration + 1) % self.migration_interval == 0:
            best = np.argmin(self.F, axis=1)
            worst = np.argmax(self.F, axis=1)
            s = np.arange(ns)
            Xb, Fb = self.X[s, best].copy(), self.F[s, best].copy()
            to = (s + 1) % ns
            self.X[to, worst[to]] = Xb
            self.F[to, worst[to]] = Fb
            self.trial[to, worst[to]] = 0
