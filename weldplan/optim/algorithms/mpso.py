"""MPSO: multi-swarm PSO with elite migration (003's MPSO baseline)."""

from __future__ import annotations

from typing import ClassVar, Literal

import numpy as np
from numpy.typing import NDArray

from weldplan.optim.algorithms.pso import C_003, PSO, W_003
from weldplan.optim.core import Context
from weldplan.optim.operators import LOGISTIC_MU


class MPSO(PSO):
    """Several PSO swarms, each guided by its own best, exchanging elites after every iteration.

    The population of ``pop_size`` particles is split into ``n_swarms`` sub-swarms of (nearly)
    equal size. Each runs the PSO update of 003 eq. 5-6 with its own swarm best as the social
    guide (``w = 0.7``, ``c1 = c2 = 1.49445`` as 003 section 4). After each iteration every
    swarm puts its best memory into a mixing pool (003 section 3.2.3); the worst personal
    memory of each swarm is replaced by the best pool elite from another swarm, when that elite
    is better.

    Deviations
    ----------
    003 does not spell out MPSO; it names it as the multi-swarm structure of ParaPA without the
    bee colony. Its pool is judged by a path-specific cross function; here (no paths) the pool is
    judged by the objective. ``pop_size`` is the total over the swarms so that budgets compare
    with single-swarm algorithms (003 uses NP = 50 per swarm).
    """

    name: ClassVar[str] = "mpso"

    def __init__(
        self,
        pop_size: int = 30,
        n_swarms: int = 3,
        w_start: float = W_003,
        w_end: float = W_003,
        c1: float = C_003,
        c2: float = C_003,
        v_max: float = 0.2,
        init: Literal["uniform", "logistic"] = "uniform",
        mu: float = LOGISTIC_MU,
    ) -> None:
        super().__init__(pop_size, w_start, w_end, c1, c2, v_max, init, mu)
        if not 1 <= n_swarms <= pop_size:
            raise ValueError(f"n_swarms must lie in [1, pop_size], got {n_swarms}")
        self.n_swarms = int(n_swarms)

    def _setup_guides(self, ctx: Context) -> None:
        self.swarm = np.arange(self.pop_size) * self.n_swarms // self.pop_size
        self._update_guides(ctx)

    def _swarm_bests(self) -> NDArray[np.intp]:
        """Index of the best personal memory of every swarm, ``(n_swarms,)``."""
        # order by (swarm, fitness): the first row of each swarm is its best
        order = np.lexsort((self.PF, self.swarm))
        first = np.searchsorted(self.swarm[order], np.arange(self.n_swarms))
        return order[first]

    def _update_guides(self, ctx: Context) -> None:
        best = self._swarm_bests()
        self.G_all = self.P[best].copy()
        i = best[int(np.argmin(self.PF[best]))]
        self.G, self.GF = self.P[i].copy(), float(self.PF[i])

    def _guide(self) -> NDArray[np.float64]:
        return self.G_all[self.swarm]

    def step(self, ctx: Context) -> None:
        super().step(ctx)
        if self.n_swarms > 1:
            self._migrate()
            self._update_guides(ctx)

    def _migrate(self) -> None:
        """Replace each swarm's worst memory by the best pool elite of the other swarms."""
        best = self._swarm_bests()
        order = np.lexsort((-self.PF, self.swarm))
        worst = order[np.searchsorted(self.swarm[order], np.arange(self.n_swarms))]
        pool_x, pool_f = self.P[best].copy(), self.PF[best].copy()
        for s in range(self.n_swarms):  # a handful of swarms, not particles
            others = np.flatnonzero(np.arange(self.n_swarms) != s)
            e = others[int(np.argmin(pool_f[others]))]
            if pool_f[e] < self.PF[worst[s]]:
                self.P[worst[s]] = pool_x[e]
                self.PF[worst[s]] = pool_f[e]
                self.X[worst[s]] = pool_x[e]
