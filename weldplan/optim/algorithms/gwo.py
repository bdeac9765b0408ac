"""Grey wolf optimiser (GWO; Mirjalili, Mirjalili & Lewis 2014), a baseline of 000."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from weldplan.optim.algorithms._common import iteration_fraction
from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds


class GWO(Optimizer):
    """Grey wolf optimiser, vectorised over wolves, leaders and dimensions.

    With the leaders ``L_k`` (alpha, beta, delta: the three best solutions found so far)::

        A_k = 2 a r1 - a,  C_k = 2 r2,  D_k = |C_k L_k - X|,  X_k = L_k - A_k D_k   (eq. 3.1-3.6)
        X <- (X_1 + X_2 + X_3) / 3                                              (eq. 3.7)

    ``r1, r2 ~ U(0, 1)`` per wolf, leader and dimension; ``a`` falls linearly from
    ``a_max = 2`` to ``a_min = 0`` (000 Table 2). Positions are clipped to the box and replace
    the pack (no greedy selection), as in the reference code.

    Deviation: the reference code overwrites alpha without shifting the old alpha to beta;
    here the leaders are always the three best distinct evaluations (of the leaders and the
    pack), which is what the paper describes.
    """

    name: ClassVar[str] = "gwo"

    def __init__(self, pop_size: int = 30, a_max: float = 2.0, a_min: float = 0.0) -> None:
        super().__init__(pop_size)
        self.a_max = float(a_max)
        self.a_min = float(a_min)

    def initialize(self, ctx: Context) -> None:
        self.X = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size)
        self.F = ctx.evaluate(self.X)
        self.L = np.empty((0, ctx.n_var))
        self.LF = np.empty(0)
        self._update_leaders()

    def _update_leaders(self) -> None:
        X = np.vstack([self.L, self.X])
        F = np.concatenate([self.LF, self.F])
        order = np.argsort(F, kind="stable")[:3]
        L, LF = X[order], F[order]
        if L.shape[0] < 3:  # fewer than three wolves: repeat the best
            pad = 3 - L.shape[0]
            L = np.vstack([L, np.repeat(L[:1], pad, axis=0)])
            LF = np.concatenate([LF, np.repeat(LF[:1], pad)])
        self.L, self.LF = L, LF

    def step(self, ctx: Context) -> None:
        rng = ctx.rng
        n, d = self.X.shape
        a = self.a_max - (self.a_max - self.a_min) * iteration_fraction(ctx)
        A = 2.0 * a * rng.random((3, n, d)) - a
        C = 2.0 * rng.random((3, n, d))
        Lb = self.L[:, None, :]
        Xk = Lb - A * np.abs(C * Lb - self.X[None])
        self.X = clip_to_bounds(Xk.mean(axis=0), ctx.lower, ctx.upper)
        self.F = ctx.evaluate(self.X)
        self._update_leaders()
