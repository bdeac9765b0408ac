"""Artificial fish swarm (AFSA) and the hybrid fish swarm of 001 (HAFSA).

Huang, Li, Jiang, Cheng. Cooperative Path Planning for Multiple Mobile Robots via HAFSA and an
Expansion Logic Strategy. Applied Sciences 9:672, 2019 (``../shared/papers/001_*``, section 2).

Every fish acts at once: the neighbourhoods come from one ``(n_pop, n_pop)`` distance matrix, the
prey trials are batches over the fish still searching, and each batch is one ``ctx.evaluate``.

Readings of the printed equations (named deviations)
----------------------------------------------------
* Minimisation. 001 writes the behaviours for a food concentration ``Y`` to be maximised, with the
  crowding test folded into ``Y_c / N_F > delta Y_i`` (eq. 2-3). We use the standard minimisation
  reading of Li et al. (2002): a fish moves to the centre (swarm) or to its best neighbour
  (follow) when that point is better, ``f_c < f_i``, and the neighbourhood is not crowded,
  ``N_F < delta * n_pop``.
* ``rand(0, 1)`` in the random displacement of eq. 1 and eq. 4 (``X + Visual * rand``) would drift
  every fish towards ``+inf``; we draw the displacement uniformly in ``[-Visual, Visual]`` per
  dimension, which is the "random state within the visual field" the text describes.
* Swarm and follow are both tried, the better move is kept (the classic AFSA rule); prey runs
  for the fish for which neither applies (not a second time as the fallback of each, which would
  evaluate a prey result the comparison almost always drops). A fish whose prey trials all fail
  makes the random move (eq. 4). Fish always move (AFSA has no greedy selection); the best
  solution is the "bulletin board", kept by ``ctx``.
* Positions leaving the box are clipped to it.
"""

from __future__ import annotations

import logging
import math

import numpy as np
from numpy.typing import NDArray

from weldplan.optim.algorithms._common import iteration_fraction
from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds

log = logging.getLogger(__name__)

#: 001 section 4: "the visual distance of an artificial fish was v = 10" on a 20-cell map, i.e.
#: half the side of the search box; the default visual is this fraction of the mean box side.
VISUAL_FRACTION = 0.5
#: 001 gives no step; one tenth of the box side is our default (step < visual, as AFSA requires).
STEP_FRACTION = 0.1


class AFSA(Optimizer):
    """Artificial fish swarm: prey, swarm, follow and random behaviours (001 eq. 1-4).

    Parameters
    ----------
    pop_size
        Number of fish ``Num`` (001 section 4: N = 50).
    visual
        Visual distance (problem units); ``None`` gives ``VISUAL_FRACTION`` of the mean box side
        (001: v = 10 on 20 x 20 maps).
    step_size
        Largest move ``step`` of eq. 1-3 (problem units); ``None`` gives ``STEP_FRACTION`` of the
        mean box side. (Named ``step_size`` because ``step`` is the optimiser's iteration.)
    delta
        Crowd factor (001 section 4: 0.618).
    try_number
        Prey attempts before the random behaviour (not given in 001; 5 is the usual choice).

    Notes
    -----
    Each iteration evaluates the swarm centres, the swarm and follow moves, up to ``try_number``
    prey probes per preying fish and the new positions: between about ``2 n_pop`` and
    ``(try_number + 3) n_pop`` solutions.
    """

    name = "afsa"

    def __init__(
        self,
        pop_size: int = 50,
        visual: float | None = None,
        step_size: float | None = None,
        delta: float = 0.618,
        try_number: int = 5,
    ) -> None:
        super().__init__(pop_size)
        if try_number < 1:
            raise ValueError(f"try_number must be >= 1, got {try_number}")
        if not 0.0 < delta:
            raise ValueError(f"crowd factor delta must be > 0, got {delta}")
        self.visual = visual
        self.step_size = step_size
        self.delta = float(delta)
        self.try_number = int(try_number)

    # --- hooks that HAFSA overrides -------------------------------------------------------
    def _reference(self, ctx: Context, F: NDArray[np.float64]) -> NDArray[np.float64]:
        """The value a candidate must beat to attract fish ``i`` (plain AFSA: ``f_i``)."""
        return F

    def _move(
        self,
        ctx: Context,
        X: NDArray[np.float64],
        T: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """Move from ``X (m, n)`` towards targets ``T (m, n)``: eq. 1-3, ``step * rand``."""
        d = T - X
        norm = np.linalg.norm(d, axis=1, keepdims=True)
        unit = np.divide(d, norm, out=np.zeros_like(d), where=norm > 0)
        return X + unit * (self._step * ctx.rng.random((X.shape[0], 1)))

    def _after_behaviours(self, ctx: Context) -> None:
        """Extra operators after the behaviours (HAFSA's detection operator)."""

    # --- the algorithm --------------------------------------------------------------------
    def initialize(self, ctx: Context) -> None:
        span = float(np.mean(ctx.upper - ctx.lower))
        self._visual = self.visual if self.visual is not None else VISUAL_FRACTION * span
        self._step = self.step_size if self.step_size is not None else STEP_FRACTION * span
        self.X = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size)
        self.F = ctx.evaluate(self.X)

    def _random_move(self, ctx: Context, X: NDArray[np.float64]) -> NDArray[np.float64]:
        """Eq. 4: a uniform displacement within the visual field."""
        return X + self._visual * ctx.rng.uniform(-1.0, 1.0, X.shape)

    def step(self, ctx: Context) -> None:
        X, F = self.X, self.F
        n = X.shape[0]
        ref = self._reference(ctx, F)
        lo, hi = ctx.lower, ctx.upper

        # Neighbourhoods: fish j is in the view of fish i when ||X_j - X_i|| < visual.
        sq = np.einsum("ij,ij->i", X, X)
        D2 = np.maximum(sq[:, None] + sq[None, :] - 2.0 * (X @ X.T), 0.0)
        nbr = D2 < self._visual**2
        np.fill_diagonal(nbr, False)
        nf = nbr.sum(axis=1)
        social = (nf > 0) & (nf < self.delta * n)

        X_new = X.copy()
        F_new = F.copy()
        best_social = np.full(n, np.inf)
        moved = np.zeros(n, dtype=bool)

        idx = np.flatnonzero(social)
        if idx.size:
            # Swarm (eq. 2): the centre of the neighbours, if it is better.
            Xc = (nbr[idx].astype(np.float64) @ X) / nf[idx, None]
            Fc = ctx.evaluate(clip_to_bounds(Xc, lo, hi))
            # Follow (eq. 3): the best neighbour, if it is better.
            Fn = np.where(nbr[idx], F[None, :], np.inf)
            jbest = np.argmin(Fn, axis=1)
            Fm = F[jbest]
            sw = Fc < ref[idx]
            fo = Fm < ref[idx]
            targets: list[tuple[NDArray[np.intp], NDArray[np.float64]]] = []
            if sw.any():
                targets.append((idx[sw], Xc[sw]))
            if fo.any():
                targets.append((idx[fo], X[jbest[fo]]))
            for rows, T in targets:
                Xm = clip_to_bounds(self._move(ctx, X[rows], T), lo, hi)
                Fm_new = ctx.evaluate(Xm)
                better = Fm_new < best_social[rows]
                r = rows[better]
                X_new[r] = Xm[better]
                F_new[r] = Fm_new[better]
                best_social[r] = Fm_new[better]
                moved[r] = True

        # Prey (eq. 1) for the fish that neither swarmed nor followed.
        todo = np.flatnonzero(~moved)
        for _ in range(self.try_number):
            if todo.size == 0:
                break
            probe = clip_to_bounds(self._random_move(ctx, X[todo]), lo, hi)
            Fp = ctx.evaluate(probe)
            ok = Fp < ref[todo]
            if ok.any():
                rows = todo[ok]
                Xm = clip_to_bounds(self._move(ctx, X[rows], probe[ok]), lo, hi)
                X_new[rows] = Xm
                moved[rows] = True
                F_new[rows] = np.nan  # evaluated below with the random movers
            todo = todo[~ok]
        # Random behaviour (eq. 4) for the fish whose every prey attempt failed.
        if todo.size:
            X_new[todo] = clip_to_bounds(self._random_move(ctx, X[todo]), lo, hi)
            F_new[todo] = np.nan
        pending = np.flatnonzero(np.isnan(F_new))
        if pending.size:
            F_new[pending] = ctx.evaluate(X_new[pending])
        self.X, self.F = X_new, F_new
        self._after_behaviours(ctx)


class HAFSA(AFSA):
    """Hybrid artificial fish swarm of 001: AFSA plus experiential learning and detection.

    Experiential learning (001 section 2.1)
        * Logarithmic step (eq. 5-7): every behaviour's move becomes
          ``X_i + log_N(p) (X_eps - X_i)`` with ``p`` the iteration (1-based) and ``N`` the
          number of iterations, so the fraction of the way to the target state ``X_eps`` grows
          from 0 to 1. With an evaluation or time budget ``N`` is ``schedule_iters`` and
          ``p / N`` is the fraction of the budget used.
        * Food concentration weight (eq. 8): ``H = w * dist`` with ``w`` in ``[1, 1.5)``; a fish's
          own food concentration is discounted by a weight ``w_i ~ U[1, w_max)`` drawn each
          iteration, so a candidate attracts it when ``f_cand < f_i + (w_i - 1) |f_i|`` (``w_i f_i``
          for the non-negative lengths of 001; the ``|f_i|`` form keeps the sense for negative
          objectives).
    Detection operator (001 section 2.2, eq. 9-11)
        After the behaviours, ``n_detect`` points are drawn uniformly in the ball of radius
        ``R(t)`` around the best solution and the best of them replaces the worst fish if better.
        ``R(t) = ceil(D / (2 k_t)) sqrt(2)`` cells for ``0 < t < count`` and ``2 sqrt(2)`` cells
        afterwards, ``D = ||best - goal|| / sqrt(2)`` in cells (eq. 10),
        ``count = floor(round(0.27 n) * 0.75)`` (eq. 11) with ``n = grid_n``, ``k_t`` the
        iteration. Generalisation (named): the cell is the box side over ``grid_n`` (001's maps
        are 20 x 20); ``goal`` is the goal point where a path problem gives one, otherwise the
        centroid of the swarm stands in for it.

    Parameters
    ----------
    w_max
        Upper end of the food concentration weight range ``[1, w_max)`` (eq. 8: 1.5).
    grid_n
        Cells per box side for the detection radius (001: 20).
    n_detect
        Points probed by the detection operator per iteration (not given in 001; ``None`` gives
        ``max(1, pop_size // 10)``).
    goal
        ``(n_var,)`` goal point for eq. 10, or ``None`` for the swarm centroid.
    schedule_iters
        ``N`` of eq. 5 when the run has no iteration budget.
    """

    name = "hafsa"

    def __init__(
        self,
        pop_size: int = 50,
        visual: float | None = None,
        step_size: float | None = None,
        delta: float = 0.618,
        try_number: int = 5,
        w_max: float = 1.5,
        grid_n: int = 20,
        n_detect: int | None = None,
        goal: NDArray[np.float64] | None = None,
        schedule_iters: int = 500,
    ) -> None:
        super().__init__(pop_size, visual, step_size, delta, try_number)
        if w_max < 1.0:
            raise ValueError(f"w_max must be >= 1, got {w_max}")
        self.w_max = float(w_max)
        self.grid_n = int(grid_n)
        self.n_detect = n_detect
        self.goal = None if goal is None else np.asarray(goal, dtype=np.float64)
        self.schedule_iters = int(schedule_iters)

    def initialize(self, ctx: Context) -> None:
        if self.goal is not None and self.goal.shape != (ctx.n_var,):
            raise ValueError(f"goal must have shape ({ctx.n_var},), got {self.goal.shape}")
        super().initialize(ctx)

    def _log_factor(self, ctx: Context) -> float:
        """``b = log_N p`` of eq. 5, in ``[0, 1]``."""
        N = ctx.max_iter if ctx.max_iter else self.schedule_iters
        if N <= 1:
            return 1.0
        p = max(1.0, iteration_fraction(ctx) * N)
        return float(min(max(math.log(p) / math.log(N), 0.0), 1.0))

    def _reference(self, ctx: Context, F: NDArray[np.float64]) -> NDArray[np.float64]:
        w = ctx.rng.uniform(1.0, self.w_max, F.shape[0])
        return F + (w - 1.0) * np.abs(F)

    def _move(
        self, ctx: Context, X: NDArray[np.float64], T: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        return X + self._log_factor(ctx) * (T - X)

    def _after_behaviours(self, ctx: Context) -> None:
        if ctx.best_x is None or ctx.exhausted():
            return
        n_var = ctx.n_var
        cell = float(np.mean(ctx.upper - ctx.lower)) / self.grid_n
        count = math.floor(round(0.27 * self.grid_n) * 0.75)
        t = ctx.iteration + 1
        best = ctx.best_x
        if t < count:
            goal = self.goal if self.goal is not None else self.X.mean(axis=0)
            D = float(np.linalg.norm(best - goal)) / (math.sqrt(2.0) * cell)
            R = math.ceil(D / (2.0 * t)) * math.sqrt(2.0) * cell
        else:
            R = 2.0 * math.sqrt(2.0) * cell
        m = self.n_detect if self.n_detect is not None else max(1, self.pop_size // 10)
        # Uniform in the n_var-ball of radius R: direction ~ normal, radius ~ R u^(1/n).
        g = ctx.rng.standard_normal((m, n_var))
        g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)
        r = R * ctx.rng.random((m, 1)) ** (1.0 / n_var)
        probe = clip_to_bounds(best + g * r, ctx.lower, ctx.upper)
        Fp = ctx.evaluate(probe)
        k = int(np.argmin(Fp))
        worst = int(np.argmax(self.F))
        if Fp[k] < self.F[worst]:
            self.X[worst] = probe[k]
            self.F[worst] = Fp[k]
