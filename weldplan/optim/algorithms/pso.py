"""Particle swarm optimisation: the standard global-best PSO and the constant-inertia PSO of 003.

The PSO family of 000 and 003 (PSO, PSO with w = 0.7, WPSO, CPSO, MPSO) shares this class; the
variants live in their own files and change only defaults, initialisation or the social guide.
"""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from numpy.typing import NDArray

from weldplan.optim.algorithms._common import iteration_fraction
from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import LOGISTIC_MU, chaotic_population, random_in_bounds

#: 003 section 4: "the acceleration factors are accepted as a constant 1.49445"
C_003 = 1.49445
#: 003 section 4: "otherwise, the w is adapted as a constant 0.7"
W_003 = 0.7


class PSO(Optimizer):
    """Global-best PSO with a linearly varying inertia weight (Shi & Eberhart 1998).

    ``V <- w V + c1 r1 (P - X) + c2 r2 (G - X)``, ``|V| <= v_max (UB - LB)``, ``X <- X + V``
    (003 eq. 5-6 with the global best ``G``), with ``r1, r2 ~ U(0, 1)`` per entry and
    ``w = w_start - (w_start - w_end) t / T`` (003 eq. 7). Positions are clipped to the box;
    personal bests ``P`` and ``G`` are updated greedily after each evaluation.

    Defaults are the "standard" PSO of Shi & Eberhart: ``w`` 0.9 -> 0.4, ``c1 = c2 = 2``,
    ``v_max = 0.2`` of the box width. (000 Table 2 lists its PSO baseline as ``c1 = c2 = 0.4,
    w = 1``; 003's PSO is ``pso-w07``.)

    Parameters
    ----------
    w_start, w_end
        Inertia weight at the first and the last iteration.
    c1, c2
        Cognitive and social acceleration.
    v_max
        Velocity limit as a fraction of ``UB - LB`` (003 uses +/-2 on 20 x 20 maps, 0.1).
    init
        ``"uniform"`` or ``"logistic"`` (chaotic initialisation, 003 eq. 4).
    mu
        Logistic-map parameter for ``init="logistic"``.
    """

    name: ClassVar[str] = "pso"

    def __init__(
        self,
        pop_size: int = 30,
        w_start: float = 0.9,
        w_end: float = 0.4,
        c1: float = 2.0,
        c2: float = 2.0,
        v_max: float = 0.2,
        init: Literal["uniform", "logistic"] = "uniform",
        mu: float = LOGISTIC_MU,
    ) -> None:
        super().__init__(pop_size)
        if init not in ("uniform", "logistic"):
            raise ValueError(f"init must be 'uniform' or 'logistic', got {init!r}")
        if v_max <= 0:
            raise ValueError(f"v_max must be positive, got {v_max}")
        self.w_start = float(w_start)
        self.w_end = float(w_end)
        self.c1 = float(c1)
        self.c2 = float(c2)
        self.v_max = float(v_max)
        self.init = init
        self.mu = float(mu)

    def _initial_population(self, ctx: Context) -> NDArray[np.float64]:
        if self.init == "logistic":
            return chaotic_population(
                ctx.rng, ctx.lower, ctx.upper, self.pop_size, map="logistic", mu=self.mu
            )
        return random_in_bounds(ctx.rng, ctx.lower, ctx.upper, self.pop_size)

    def initialize(self, ctx: Context) -> None:
        self.vlim = self.v_max * (ctx.upper - ctx.lower)
        self.X = self._initial_population(ctx)
        self.V = ctx.rng.uniform(-1.0, 1.0, self.X.shape) * self.vlim
        self.F = ctx.evaluate(self.X)
        self.P = self.X.copy()
        self.PF = self.F.copy()
        self._setup_guides(ctx)

    def _setup_guides(self, ctx: Context) -> None:
        """Initialise the social guide (the global best for plain PSO)."""
        self._update_guides(ctx)

    def _update_guides(self, ctx: Context) -> None:
        i = int(np.argmin(self.PF))
        self.G = self.P[i].copy()
        self.GF = float(self.PF[i])

    def _guide(self) -> NDArray[np.float64]:
        """Social guide ``(N, D)`` or ``(D,)`` for the velocity update."""
        return self.G

    def inertia(self, ctx: Context) -> float:
        frac = iteration_fraction(ctx)
        return self.w_start - (self.w_start - self.w_end) * frac

    def step(self, ctx: Context) -> None:
        rng = ctx.rng
        w = self.inertia(ctx)
        r1 = rng.random(self.X.shape)
        r2 = rng.random(self.X.shape)
        V = w * self.V + self.c1 * r1 * (self.P - self.X) + self.c2 * r2 * (self._guide() - self.X)
        self.V = np.clip(V, -self.vlim, self.vlim)
        self.X = np.clip(self.X + self.V, ctx.lower, ctx.upper)
        self.F = ctx.evaluate(self.X)
        better = self.F < self.PF
        self.P[better] = self.X[better]
        self.PF[better] = self.F[better]
        self._update_guides(ctx)


class PSOW07(PSO):
    """003's PSO baseline: constant inertia weight ``w = 0.7``, ``c1 = c2 = 1.49445``."""

    name: ClassVar[str] = "pso-w07"

    def __init__(
        self,
        pop_size: int = 30,
        w_start: float = W_003,
        w_end: float = W_003,
        c1: float = C_003,
        c2: float = C_003,
        v_max: float = 0.2,
        init: Literal["uniform", "logistic"] = "uniform",
        mu: float = LOGISTIC_MU,
    ) -> None:
        super().__init__(pop_size, w_start, w_end, c1, c2, v_max, init, mu)
