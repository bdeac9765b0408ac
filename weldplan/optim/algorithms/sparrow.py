"""Sparrow search algorithm (SSA) of Xue & Shen, named beside LSO as a baseline for 002.

Xue Jiankai, Shen Bo. A novel swarm intelligence optimization approach: sparrow search
algorithm. Systems Science & Control Engineering 8(1):22-34, 2020 (eq. 3-5).

Fit to 002: 002's comparison tables name WOA and LSO, not SSA (it cites sparrow-search work
only in its references); SSA is here because issue 6 lists it, as the original paper states it.

The population is ranked by historical best each iteration (``i`` = 1-based rank):

* producers, the best ``PD`` fraction (eq. 3), with ``R2 ~ U(0, 1)`` once per iteration:
  ``x = p_i exp(-i / (alpha T))`` if ``R2 < ST`` (``alpha ~ U(0, 1]`` per producer), otherwise
  ``x = p_i + Q L`` (``Q ~ N(0, 1)``, ``L`` a row of ones);
* scroungers, the rest (eq. 4): for ``i > n / 2`` ``x = Q exp((x_worst - p_i) / i^2)``, otherwise
  ``x = x_P + |p_i - x_P| A^+ L`` with ``x_P`` the best producer after its move and ``A`` a row
  of random +-1 (``A^+ = A^T (A A^T)^-1 = A^T / D``: every coordinate moves by the same
  ``sum_j A_j |p_ij - x_Pj| / D``);
* scouts, a random ``SD`` fraction (eq. 5): ``x = x_best + beta |p_i - x_best|`` (``beta ~ N(0,1)``
  per dimension) if ``f_i > f_best``, else ``x = p_i + K |p_i - x_worst| / (f_i - f_worst + eps)``
  (``K ~ U(-1, 1)``).

Each phase is one batch evaluation; the historical bests ``p`` are kept greedily ("if the new
location is better than before, update it", Xue & Shen Algorithm 1).

Named readings
--------------
* ``T`` (the maximum iteration count in eq. 3) is ``ctx.max_iter`` when the run has one, else
  ``schedule_iters``. ``x_worst`` is the current position of the sparrow with the worst
  historical best, as in the authors' code. Positions are clipped.
* Historical bests are updated after each phase (the authors' code compares only the last
  position of an iteration with the memory); the difference is only which improvements are kept.
"""

from __future__ import annotations

import logging

import numpy as np

from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds

log = logging.getLogger(__name__)

_EPS = 1e-50


class SSA(Optimizer):
    """Sparrow search algorithm (Xue & Shen 2020).

    Parameters
    ----------
    pop_size
        Sparrows ``n`` (002's protocol: 30).
    producer_fraction
        ``PD`` (Xue & Shen: 20 %).
    scout_fraction
        ``SD`` (Xue & Shen: 10 %).
    safety_threshold
        ``ST`` in ``[0.5, 1]`` (Xue & Shen: 0.8).
    schedule_iters
        ``T`` of eq. 3 when the run has no iteration budget.
    """

    name = "ssa"

    def __init__(
        self,
        pop_size: int = 30,
        producer_fraction: float = 0.2,
        scout_fraction: float = 0.1,
        safety_threshold: float = 0.8,
        schedule_iters: int = 500,
    ) -> None:
        super().__init__(pop_size)
        if pop_size < 2:
            raise ValueError("SSA needs pop_size >= 2")
        self.producer_fraction = float(producer_fraction)
        self.scout_fraction = float(scout_fraction)
        self.safety_threshold = float(safety_threshold)
        self.schedule_iters = int(schedule_iters)

    def initialize(self, ctx: Context) -> None:
        self.X = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size)
        self.F = ctx.evaluate(self.X)
        self.P = self.X.copy()
        self.Pf = self.F.copy()

    def _keep(self, rows: np.ndarray, X: np.ndarray, F: np.ndarray) -> None:
        self.X[rows] = X
        self.F[rows] = F
        better = F < self.Pf[rows]
        self.P[rows[better]] = X[better]
        self.Pf[rows[better]] = F[better]

    def step(self, ctx: Context) -> None:
        rng = ctx.rng
        lo, hi = ctx.lower, ctx.upper
        n, D = self.P.shape
        T = ctx.max_iter if ctx.max_iter else self.schedule_iters
        order = np.argsort(self.Pf, kind="stable")
        worst_i = int(order[-1])
        x_worst = self.X[worst_i].copy()
        f_worst = float(self.Pf[worst_i])
        n_prod = min(max(1, round(self.producer_fraction * n)), n)

        # Producers (eq. 3).
        prod = order[:n_prod]
        rank = np.arange(1, n_prod + 1, dtype=np.float64)
        if rng.random() < self.safety_threshold:
            alpha = 1.0 - rng.random(n_prod)  # (0, 1]
            Xp = self.P[prod] * np.exp(-rank / (alpha * T))[:, None]
        else:
            Xp = self.P[prod] + rng.standard_normal((n_prod, 1))
        Xp = clip_to_bounds(Xp, lo, hi)
        Fp = ctx.evaluate(Xp)
        self._keep(prod, Xp, Fp)
        x_P = Xp[int(np.argmin(Fp))]

        # Scroungers (eq. 4).
        scr = order[n_prod:]
        if scr.size:
            rank = np.arange(n_prod + 1, n + 1, dtype=np.float64)
            hungry = rank > n / 2.0
            Ps = self.P[scr]
            Xs = np.empty_like(Ps)
            q = rng.standard_normal((scr.size, 1))
            with np.errstate(over="ignore"):
                Xs[hungry] = q[hungry] * np.exp((x_worst - Ps[hungry]) / rank[hungry, None] ** 2)
            A = rng.choice(np.array([-1.0, 1.0]), size=(scr.size, D))
            shift = (np.abs(Ps - x_P) * A).sum(axis=1) / D
            Xs[~hungry] = x_P + shift[~hungry, None]
            Xs = clip_to_bounds(np.nan_to_num(Xs, nan=0.0, posinf=np.inf, neginf=-np.inf), lo, hi)
            Fs = ctx.evaluate(Xs)
            self._keep(scr, Xs, Fs)

        # Scouts (eq. 5): a random SD fraction, aware of danger.
        n_sd = min(max(1, round(self.scout_fraction * n)), n)
        sc = rng.permutation(n)[:n_sd]
        b = int(np.argmin(self.Pf))
        x_best, f_best = self.P[b].copy(), float(self.Pf[b])
        Pc, Fc = self.P[sc], self.Pf[sc]
        edge = Fc > f_best
        beta = rng.standard_normal((n_sd, D))
        K = rng.uniform(-1.0, 1.0, (n_sd, 1))
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            # inf - inf when memories hold non-finite fitness: NaN, repaired to 0 below
            Xc = np.where(
                edge[:, None],
                x_best + beta * np.abs(Pc - x_best),
                Pc + K * np.abs(Pc - x_worst) / ((Fc - f_worst)[:, None] + _EPS),
            )
        Xc = clip_to_bounds(np.nan_to_num(Xc, nan=0.0, posinf=np.inf, neginf=-np.inf), lo, hi)
        Fc_new = ctx.evaluate(Xc)
        self._keep(sc, Xc, Fc_new)
