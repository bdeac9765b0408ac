"""Artificial bee colony (ABC) and its multi-swarm variant (MABC): the bee baselines of 003.

ABC: Karaboga & Basturk, J. Global Optim. 39:459-471, 2007, as restated in 003 section 2.1
(``../shared/papers/003_*``): employed bees (eq. 1), onlookers choosing food sources by roulette
(eq. 2), scouts re-sampling abandoned sources (eq. 3).

Named deviations (vectorisation)
--------------------------------
* Karaboga's employed and onlooker phases visit the sources one after another, so a bee may copy
  a neighbour that was improved a moment earlier. Here every bee of a phase searches from the
  colony as it was at the start of the phase (one batch, one ``ctx.evaluate``). When several
  onlookers land on one source the best candidate competes with it (greedy); a source that no
  onlooker improves has its trial counter raised once per unsuccessful onlooker.
* Candidates leaving the box are clipped to it.
"""

from __future__ import annotations

import logging

import numpy as np
from numpy.typing import NDArray

from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds, roulette

log = logging.getLogger(__name__)

#: 003 section 5.2: "the look limitation is adapted as 5 x NP" for ABC and MABC.
LIMIT_FACTOR = 5


def abc_fitness(F: NDArray[np.float64]) -> NDArray[np.float64]:
    """Karaboga's fitness of objective values ``F (n,)``: ``1 / (1 + f)`` for ``f >= 0``, else
    ``1 + |f|``; non-negative, larger is better (the ``fit_i`` of 003 eq. 2)."""
    F = np.asarray(F, dtype=np.float64)
    out = np.where(F >= 0, 1.0 / (1.0 + np.abs(F)), 1.0 + np.abs(F))
    return np.where(np.isfinite(F), out, 0.0)


def neighbour_search(
    rng: np.random.Generator,
    X: NDArray[np.float64],
    rows: NDArray[np.intp],
    pool: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Eq. 1: ``v_ij = x_ij + phi (x_ij - x_kj)`` for one random ``j`` and partner ``k != i``.

    Parameters
    ----------
    X
        ``(n, n_var)`` food sources.
    rows
        ``(m,)`` index of the source each bee exploits.
    pool
        ``(n, n_var)`` sources partners are drawn from (``X`` itself in ABC).

    Returns
    -------
    ``(m, n_var)`` candidates (not clipped)
    """
    n, n_var = pool.shape
    m = rows.shape[0]
    if n > 1:
        k = rng.integers(0, n - 1, m)
        k = k + (k >= rows)  # uniform over the sources other than the bee's own
    else:
        k = np.zeros(m, dtype=np.intp)
    j = rng.integers(0, n_var, m)
    phi = rng.uniform(-1.0, 1.0, m)
    V = X[rows].copy()
    r = np.arange(m)
    V[r, j] = V[r, j] + phi * (V[r, j] - pool[k, j])
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
        abc_cycle(ctx, self.X, self.F, self.trial, self._limit())


def abc_cycle(
    ctx: Context,
    X: NDArray[np.float64],
    F: NDArray[np.float64],
    trial: NDArray[np.int64],
    limit: int,
) -> None:
    """One ABC cycle on the colony ``(X (n, n_var), F (n,), trial (n,))``, updated in place."""
    rng = ctx.rng
    n = X.shape[0]
    lo, hi = ctx.lower, ctx.upper
    rows = np.arange(n)
    # Employed bees (eq. 1) with greedy selection.
    V = clip_to_bounds(neighbour_search(rng, X, rows, X), lo, hi)
    Fv = ctx.evaluate(V)
    better = Fv < F
    X[better] = V[better]
    F[better] = Fv[better]
    trial[better] = 0
    trial[~better] += 1
    # Onlookers: sources by roulette on fitness (eq. 2), then eq. 1 from the chosen source.
    chosen = np.asarray(roulette(rng, abc_fitness(F), size=n), dtype=np.intp)
    V = clip_to_bounds(neighbour_search(rng, X, chosen, X), lo, hi)
    Fv = ctx.evaluate(V)
    order = np.lexsort((Fv, chosen))  # by source, best candidate first
    first = np.ones(n, dtype=bool)
    first[1:] = chosen[order][1:] != chosen[order][:-1]
    best_c = order[first]  # best candidate of each chosen source
    src = chosen[best_c]
    imp = Fv[best_c] < F[src]
    X[src[imp]] = V[best_c[imp]]
    F[src[imp]] = Fv[best_c[imp]]
    trial[src[imp]] = 0
    visits = np.bincount(chosen, minlength=n)
    not_improved = np.ones(n, dtype=bool)
    not_improved[src[imp]] = False
    trial[not_improved] += visits[not_improved]
    # Scout (eq. 3): the most exhausted source, if past the limit, is re-sampled.
    s = int(np.argmax(trial))
    if trial[s] > limit and not ctx.exhausted():
        X[s] = random_in_bounds(rng, lo, hi, 1)[0]
        F[s] = ctx.evaluate(X[s : s + 1])[0]
        trial[s] = 0


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
        # One cycle per sub-colony (n_swarms is small): partners must come from the bee's own
        # colony, which a single cycle on the stacked colonies would not guarantee.
        ns = self._ns
        for s in range(ns):
            if ctx.exhausted():
                break
            abc_cycle(ctx, self.X[s], self.F[s], self.trial[s], self._lim)
        if ns > 1 and (ctx.iteration + 1) % self.migration_interval == 0:
            best = np.argmin(self.F, axis=1)
            worst = np.argmax(self.F, axis=1)
            s = np.arange(ns)
            Xb, Fb = self.X[s, best].copy(), self.F[s, best].copy()
            to = (s + 1) % ns
            self.X[to, worst[to]] = Xb
            self.F[to, worst[to]] = Fb
            self.trial[to, worst[to]] = 0
