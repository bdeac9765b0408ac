"""ACO_R: ant colony optimisation for continuous domains (Socha & Dorigo 2008).

Paper 003 lists "ACO" among its baselines (Tables 1-4) without saying which ant colony it ran.
The segment encoding is a continuous box (the y' offsets), so weldplan uses the standard
continuous ant colony, ACO_R, with the parameters of Socha & Dorigo (2008), *Ant colony
optimization for continuous domains*, EJOR 185(3), 1155-1173. This is our choice, not 003's.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import clip_to_bounds, random_in_bounds, roulette

#: Socha & Dorigo 2008, sec. 5 (the parameters of their benchmark runs)
ACOR_ARCHIVE = 50
ACOR_Q = 1e-4
ACOR_XI = 0.85


class ACOR(Optimizer):
    """Continuous ant colony with a solution archive, vectorised over ants and dimensions.

    The archive holds the ``k`` best solutions ``s_l`` found so far, sorted by fitness. Rank
    ``l = 1..k`` gets the weight of a Gaussian over ranks (Socha & Dorigo eq. 4)::

        w_l = exp(-(l - 1)^2 / (2 q^2 k^2)) / (q k sqrt(2 pi))

    Each ant picks one archive solution ``l`` with probability ``p_l = w_l / sum w`` (eq. 5)
    and samples every dimension ``i`` from ``N(s_l^i, sigma_l^i)`` with (eq. 6)::

        sigma_l^i = xi * sum_e |s_e^i - s_l^i| / (k - 1)

    The new solutions join the archive and the worst are dropped to keep ``k``.

    Parameters
    ----------
    pop_size
        Ants per iteration ``m``. Socha & Dorigo use ``m = 2``; weldplan's default is the
        population of the protocol it runs in (003: NP = 50), so ACO spends the same
        evaluations per iteration as the other columns.
    archive_size
        ``k``, 50 (Socha & Dorigo).
    q
        Locality of the rank weights, ``1e-4`` (Socha & Dorigo; small q = elitist: nearly
        every ant samples around the best solution).
    xi
        Pheromone evaporation analogue, the width of the kernels relative to the archive's
        spread, 0.85 (Socha & Dorigo).

    Deviations
    ----------
    - Samples outside the box are clipped to it (Socha & Dorigo's benchmarks are unbounded).
    - ``m`` defaults to the population size (see above).
    - ``X`` is the archive, so paper 003's diversity DI (eq. 18) is measured over it.
    """

    name: ClassVar[str] = "aco"

    def __init__(
        self,
        pop_size: int = 30,
        archive_size: int = ACOR_ARCHIVE,
        q: float = ACOR_Q,
        xi: float = ACOR_XI,
    ) -> None:
        super().__init__(pop_size)
        if archive_size < 2:
            raise ValueError(f"archive_size must be >= 2, got {archive_size}")
        if q <= 0 or xi <= 0:
            raise ValueError(f"q and xi must be positive, got q={q}, xi={xi}")
        self.archive_size = int(archive_size)
        self.q = float(q)
        self.xi = float(xi)

    def initialize(self, ctx: Context) -> None:
        k = self.archive_size
        X = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, k)
        F = ctx.evaluate(X)
        order = np.argsort(F, kind="stable")
        self.X, self.F = X[order], F[order]
        ranks = np.arange(k)
        qk = self.q * k
        # eq. 4 without its constant factor 1 / (q k sqrt(2 pi)), which cancels in eq. 5
        self.p = np.exp(-(ranks**2) / (2.0 * qk * qk))
        self.p /= self.p.sum()

    def step(self, ctx: Context) -> None:
        rng = ctx.rng
        k, d = self.X.shape
        m = self.pop_size
        guide = roulette(rng, self.p, m)  # (m,)
        S = self.X[guide]  # (m, d)
        spread = np.abs(self.X[None, :, :] - S[:, None, :]).sum(axis=1) / (k - 1)  # (m, d)
        sigma = self.xi * spread
        Y = clip_to_bounds(S + sigma * rng.standard_normal((m, d)), ctx.lower, ctx.upper)
        FY = ctx.evaluate(Y)
        X = np.vstack([self.X, Y])
        F = np.concatenate([self.F, FY])
        keep = np.argsort(F, kind="stable")[:k]
        self.X, self.F = X[keep], F[keep]
