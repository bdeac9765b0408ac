"""Whale optimisation algorithm (WOA; Mirjalili & Lewis 2016), a baseline of 000 and 002."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from weldplan.optim.algorithms._common import iteration_fraction
from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds


class WOA(Optimizer):
    """Whale optimisation algorithm, vectorised over whales and dimensions.

    Per whale, scalars ``A = 2 a r1 - a``, ``C = 2 r2``, ``l ~ U(-1, 1)`` (as ``(a2 - 1) rand + 1``
    with ``a2`` from -1 to -2 in the reference code), ``p ~ U(0, 1)``, then::

        p < 0.5, |A| < 1:   X <- X* - A |C X* - X|                  encircling   (eq. 2.1-2.2)
        p < 0.5, |A| >= 1:  X <- X_rand - A |C X_rand - X|          search       (eq. 2.7-2.8)
        p >= 0.5:           X <- |X* - X| e^(b l) cos(2 pi l) + X*  bubble net   (eq. 2.5)

    with ``X*`` the best solution so far, ``b = 1`` and ``a`` falling linearly from 2 to 0
    (000 Table 2). As in the reference code the random whale ``X_rand`` is drawn per dimension.
    Positions are clipped to the box and replace the pod.
    """

    name: ClassVar[str] = "woa"

    def __init__(
        self, pop_size: int = 30, a_max: float = 2.0, a_min: float = 0.0, b: float = 1.0
    ) -> None:
        super().__init__(pop_size)
        self.a_max = float(a_max)
        self.a_min = float(a_min)
        self.b = float(b)

    def initialize(self, ctx: Context) -> None:
        self.X = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size)
        self.F = ctx.evaluate(self.X)
        i = int(np.argmin(self.F))
        self.best_x, self.best_f = self.X[i].copy(), float(self.F[i])

    def step(self, ctx: Context) -> None:
        rng = ctx.rng
        n, d = self.X.shape
        frac = iteration_fraction(ctx)
        a = self.a_max - (self.a_max - self.a_min) * frac
        a2 = -1.0 - frac
        A = (2.0 * a * rng.random(n) - a)[:, None]
        C = 2.0 * rng.random(n)[:, None]
        l = ((a2 - 1.0) * rng.random(n) + 1.0)[:, None]
        p = rng.random(n)[:, None]
        Xs = self.best_x[None, :]
        R = self.X[rng.integers(0, n, (n, d)), np.arange(d)]
        encircle = Xs - A * np.abs(C * Xs - self.X)
        search = R - A * np.abs(C * R - self.X)
        spiral = np.abs(Xs - self.X) * np.exp(self.b * l) * np.cos(2.0 * np.pi * l) + Xs
        X = np.where(p < 0.5, np.where(np.abs(A) < 1.0, encircle, search), spiral)
        self.X = clip_to_bounds(X, ctx.lower, ctx.upper)
        self.F = ctx.evaluate(self.X)
        i = int(np.argmin(self.F))
        if self.F[i] < self.best_f:
            self.best_x, self.best_f = self.X[i].copy(), float(self.F[i])
