"""Slime mould algorithm (SMA; Li, Chen, Wang, Heidari & Mirjalili 2020).

As restated in 000 section 3 (eq. 1-5) and 002 section 1.1 (eq. 1-5), following the authors'
reference code where the restatements are silent.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from weldplan.optim.algorithms._common import iteration_fraction
from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds

#: 002 section 1.1: "z = 0.03 gives the best performance" (000 Table 2 uses 0.3)
SMA_Z = 0.03
_EPS = np.finfo(np.float64).eps


class SMA(Optimizer):
    """Slime mould algorithm, vectorised over population and dimensions.

    One iteration (002 eq. 1, 000 eq. 5), for every mould ``i`` and dimension ``j``::

        X_i      <- rand * (UB - LB) + LB                              if rand < z
        X_ij     <- X_b,j + vb_ij (W_ij X_A,j - X_B,j)                 elif r_ij < p_i
        X_ij     <- vc_ij X_ij                                          otherwise

    with ``p_i = tanh |S(i) - DF|`` (eq. 2; DF the best fitness so far), ``vb ~ U(-a, a)``,
    ``a = arctanh(1 - t/T)`` (eq. 3), ``vc ~ U(-b, b)`` with ``b = 1 - t/T`` and the weights
    (000 eq. 4, 002 eq. 5), ``W = 1 +/- r log10((bF - S(i)) / (bF - wF) + 1)``, ``+`` for the
    better half of the sorted population, ``-`` for the rest, ``r ~ U(0, 1)`` per entry.
    ``X_A``, ``X_B`` are moulds drawn at random per entry. Positions are clipped to the box and
    the whole population is replaced (no greedy selection), as in the reference code.

    Parameters
    ----------
    pop_size
        N; 30 in 000 Table 2 and 002.
    z
        Probability of a random restart of a mould: 0.03 (002, the default); 000 Table 2 uses 0.3.
    init
        ``"uniform"`` (the papers): the initial population is uniform in the box.
        ``"problem"`` (an improvement, off by default): the Problem's own
        ``initial_population(rng, n)`` when it has one (the spline paths seed a third of the
        moulds along a coarse grid path), uniform otherwise.

    Notes
    -----
    At the last iteration ``b = 1 - t/T = 0``, so every mould that takes the ``vc * X`` branch
    lands exactly on the origin (this happens in the reference code too). On functions whose
    optimum is the origin (all of 002 Table 1) that alone yields the exact zeros of 002 Table 2;
    shift the optimum (``get_function(..., shift=...)``, ``bench functions --shift``) to see
    the algorithm without that help.

    Deviations
    ----------
    - ``vc`` is drawn from ``U(-b, b)`` with ``b`` falling linearly from 1 to 0 (the reference
      code); the papers only say "vc decreases linearly from 1 to 0".
    - The reference code updates moulds one at a time, so later moulds may read already-moved
      ``X_A``/``X_B``; here every mould reads the positions at the start of the iteration
      (Jacobi instead of Gauss-Seidel order), which is what makes it vectorisable.
    - A random restart draws one uniform number per dimension (000 eq. 5, 002 eq. 1); the
      reference code draws one per mould.
    - ``a = arctanh(1 - t/T)`` uses the 1-based ``t`` (see ``iteration_fraction``), so it is
      finite on the first iteration.
    """

    name: ClassVar[str] = "sma"

    def __init__(self, pop_size: int = 30, z: float = SMA_Z, init: str = "uniform") -> None:
        super().__init__(pop_size)
        if not 0.0 <= z <= 1.0:
            raise ValueError(f"z must lie in [0, 1], got {z}")
        if init not in ("uniform", "problem"):
            raise ValueError(f"init must be 'uniform' or 'problem', got {init!r}")
        self.z = float(z)
        self.init = init

    # -- hooks for the variants ------------------------------------------------------------
    def _initial_population(self, ctx: Context) -> NDArray[np.float64]:
        make = getattr(ctx.problem, "initial_population", None)
        if self.init == "problem" and make is not None:
            X = np.asarray(make(ctx.rng, self.pop_size), dtype=np.float64)
            return clip_to_bounds(X, ctx.lower, ctx.upper)
        return random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size)

    def _after_update(self, ctx: Context) -> None:
        """Extra operators of a variant, run after the position update and its evaluation."""

    # -- the algorithm -----------------------------------------------------------------------
    def initialize(self, ctx: Context) -> None:
        self.X = self._initial_population(ctx)
        self.F = ctx.evaluate(self.X)
        i = int(np.argmin(self.F))
        self.best_x = self.X[i].copy()
        self.best_f = float(self.F[i])

    def _update_best(self) -> None:
        i = int(np.argmin(self.F))
        if self.F[i] < self.best_f:
            self.best_f = float(self.F[i])
            self.best_x = self.X[i].copy()

    def weights(self, rng: np.random.Generator) -> NDArray[np.float64]:
        """Weights ``W (N, D)`` of 000 eq. 4 / 002 eq. 5 for the current population."""
        n, d = self.X.shape
        order = np.argsort(self.F, kind="stable")
        Fs = self.F[order]
        finite = np.isfinite(Fs)
        bF = Fs[0]
        if not np.isfinite(bF):
            ratio = np.zeros(n)
        else:
            wF = Fs[finite].max()
            with np.errstate(invalid="ignore", divide="ignore"):
                ratio = (bF - Fs) / (bF - wF - _EPS)
            ratio = np.where(finite, ratio, 1.0)
        lg = np.log10(ratio + 1.0)
        sign = np.where(np.arange(n) < n / 2, 1.0, -1.0)
        W = np.empty((n, d))
        W[order] = 1.0 + sign[:, None] * rng.random((n, d)) * lg[:, None]
        return W

    def step(self, ctx: Context) -> None:
        rng = ctx.rng
        n, d = self.X.shape
        frac = iteration_fraction(ctx)
        a = float(np.arctanh(min(1.0 - frac, 1.0 - 1e-6)))
        b = 1.0 - frac
        W = self.weights(rng)
        with np.errstate(invalid="ignore"):
            p = np.tanh(np.abs(self.F - self.best_f))
        p = np.nan_to_num(p, nan=1.0)
        vb = rng.uniform(-a, a, (n, d))
        vc = rng.uniform(-b, b, (n, d))
        r = rng.random((n, d))
        A = rng.integers(0, n, (n, d))
        B = rng.integers(0, n, (n, d))
        cols = np.arange(d)
        approach = self.best_x + vb * (W * self.X[A, cols] - self.X[B, cols])
        X = np.where(r < p[:, None], approach, vc * self.X)
        restart = rng.random(n) < self.z
        if restart.any():
            X[restart] = random_in_bounds(rng, ctx.lower, ctx.upper, int(restart.sum()))
        self.X = clip_to_bounds(X, ctx.lower, ctx.upper)
        self.F = ctx.evaluate(self.X)
        self._update_best()
        self._after_update(ctx)
