"""ParaPA: the parasitism-relation PSO-ABC of 003, with multi-swarm elite exchange.

Ren, Gao, Shen, Li, Jiang. A Novel Swarm Intelligence Algorithm with a Parasitism-Relation-Based
Structure for Mobile Robot Path Planning. Sensors 23:1751, 2023 (``../shared/papers/003_*``,
section 3 and the settings of section 5.2).

The cross function
------------------
The elites a swarm receives are judged by a pluggable *cross function* instead of the objective
(003 section 3.2.3, Algorithm 1, eq. 17). Its contract:

``cross(candidates, elites) -> penalties``
    ``candidates`` is ``(m, n_var) float``, ``elites`` is ``(E, n_var) float`` (the elites of the
    swarm being served); it returns ``(m,) float`` penalties, **lower is better**: a low penalty
    means the candidate overlaps the elites little (003: the number of segment intersections of
    the candidate path with the elite paths, ``sum_e sum_n Cp_n^e``, eq. 17). It must not modify
    its arguments, must be deterministic, and is not counted against the evaluation budget (it
    never calls the objective). ParaPA calls it twice per swarm per exchange: on the foreign elites
    of the mixing pool, then on the chosen ones mixed with the swarm's worst memories.

The default, :func:`distance_cross`, is the negative mean Euclidean distance to the elites (the
candidate most different from the swarm's elites wins), the continuous analogue of "the elite who
has the greatest difference from others in the mixed group" (003 section 4.3).

Readings and named deviations
-----------------------------
* Population: ``pop_size`` is the total over ``n_swarms`` swarms (default 3 x 50; 003 section 5.2:
  NP = 50 per swarm; the number of swarms is not stated, 3 is our default).
* Hosts (the onlooker/nectar layer): ``NP / 5`` per swarm (003 section 5.2), initialised as the
  best ``NP / 5`` chaotic particles (section 3.2.1). Each particle picks its host by roulette on
  ABC fitness (eq. 2) every iteration and uses it in place of gbest (eq. 5). A host is replaced by
  the best particle that chose it when that particle is better (its visit count restarts);
  otherwise its count grows by the visits; past ``3 NP`` (section 3.2.2) it is re-sampled uniformly
  (eq. 3) with no memory kept.
* ``r1, r2 ~ U[0, 2]`` are drawn per particle and dimension; ``w`` falls linearly 0.9 -> 0.1 over
  the budget (eq. 7, ``g / Maxgen`` read as the fraction of the budget used). Velocities start
  at 0 and are clamped to ``+-v_max_fraction * (upper - lower)`` (003: Vmax = 2 on 20 x 20 maps,
  0.1 of the side).
* Out-of-box positions are clipped (003 regenerates the whole path; that rule belongs to its
  path encoding).
* Exchange (Algorithm 1), every ``exchange_interval`` iterations: each swarm puts its
  ``n_elites`` best personal memories (by objective) in the pool; for swarm ``s`` the
  ``n_cross`` foreign elites with the lowest cross penalty against ``s``'s elites are mixed with
  ``s``'s ``n_worst`` worst memories; the one of lowest cross penalty (pool-output group of 1)
  replaces the particle of ``s`` with the worst memory. That particle keeps the better of its
  old memory and the incoming elite ("the replaced individuals always keep the best memories").
  All swarms draw from the pool as it was before any replacement.

Hooks for subclasses
--------------------
Two methods are identities here and exist for the multimodal planner
(:mod:`weldplan.planar.multimodal`): :meth:`ParaPA._scores` turns objective values into the
values each swarm ranks by (roulette on hosts, memory and host updates, the exchange), and
:meth:`ParaPA._respawn` places the hosts abandoned at the nectar limit (003 Algorithm 2 repairs
them there). The arrays ``F``, ``Pf`` and ``Of`` always hold objective values.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError
from weldplan.optim.algorithms._common import iteration_fraction
from weldplan.optim.algorithms.bee import abc_fitness, roulette_rows
from weldplan.optim.core import Context, Optimizer
from weldplan.optim.operators import chaotic_population, clip_to_bounds, random_in_bounds

log = logging.getLogger(__name__)

CrossFunction = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def distance_cross(
    candidates: NDArray[np.float64], elites: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Default cross function: ``-mean_e ||c - e||`` per candidate, ``(m,)``; lower is better."""
    d = candidates[:, None, :] - elites[None, :, :]
    return -np.sqrt(np.einsum("mek,mek->me", d, d)).mean(axis=1)


@dataclass(frozen=True)
class ParaPASettings:
    """ParaPA's parameters (003 section 3 and the settings of section 5.2), validated once.

    Attributes
    ----------
    n_swarms
        Number of swarms (not stated in 003; 3).
    w_max, w_min
        Inertia weight range, falling linearly (eq. 7: 0.9 -> 0.1).
    r_max
        ``r1, r2 ~ U[0, r_max]`` (section 3.2.2: 2).
    onlooker_fraction
        Hosts per swarm as a fraction of NP (section 5.2: 1/5).
    limit_factor
        A host is abandoned after ``limit_factor * NP`` visits without improvement (section
        3.2.2: 3).
    v_max_fraction
        Velocity clamp as a fraction of the box side (section 5.2: Vmax = 2 on 20-wide maps).
    n_elites, n_cross, n_worst
        Elites per swarm in the pool (section 5.2: 10), elites chosen by the cross function (3)
        and worst memories mixed with them (not stated; 3).
    exchange_interval
        Iterations between exchanges (section 3.2.3: after each evolution, 1).
    cross
        Cross function (see the module docstring); ``None`` gives :func:`distance_cross`.
    chaos_mu
        Logistic map parameter of the initialisation (eq. 4: mu = 4).
    """

    n_swarms: int = 3
    w_max: float = 0.9
    w_min: float = 0.1
    r_max: float = 2.0
    onlooker_fraction: float = 0.2
    limit_factor: float = 3.0
    v_max_fraction: float = 0.1
    n_elites: int = 10
    n_cross: int = 3
    n_worst: int = 3
    exchange_interval: int = 1
    cross: CrossFunction | None = None
    chaos_mu: float = 4.0

    def __post_init__(self) -> None:
        if self.n_swarms < 1:
            raise ConfigError(f"n_swarms must be >= 1, got {self.n_swarms}", field="n_swarms")
        if self.exchange_interval < 1:
            raise ConfigError("exchange_interval must be >= 1", field="exchange_interval")
        for f in fields(self):  # the types the algorithm computes with
            if f.type in ("int", "float"):
                cast = int if f.type == "int" else float
                object.__setattr__(self, f.name, cast(getattr(self, f.name)))


class ParaPA(Optimizer):
    """Parasitism-relation PSO-ABC with multi-swarm elite exchange (003 section 3).

    Parameters
    ----------
    pop_size
        Particles over all swarms (003: NP = 50 per swarm; default 3 swarms, 150).
    settings
        The algorithm's parameters (:class:`ParaPASettings`, the paper's by default).
    **options
        Any field of :class:`ParaPASettings` by name (``n_swarms=4``, ``cross=f``...), laid over
        ``settings``: the registry builds every optimiser from keywords.

    Each field of the settings is also an attribute of the optimiser (``self.n_swarms``...).
    """

    name = "parapa"

    def __init__(
        self, pop_size: int = 150, settings: ParaPASettings | None = None, **options: Any
    ) -> None:
        super().__init__(pop_size)
        st = replace(settings or ParaPASettings(), **options)
        if pop_size < st.n_swarms:
            raise ConfigError(
                f"need pop_size >= n_swarms >= 1, got {pop_size} and {st.n_swarms}",
                field="pop_size",
            )
        self.settings = st
        for f in fields(st):
            setattr(self, f.name, getattr(st, f.name))

    def initialize(self, ctx: Context) -> None:
        S = self.n_swarms
        NP = self.pop_size // S
        D = ctx.n_var
        self._np = NP
        self._no = max(1, round(self.onlooker_fraction * NP))
        self._limit = self.limit_factor * NP
        self._vmax = self.v_max_fraction * (ctx.upper - ctx.lower)
        self._cross = self.cross if self.cross is not None else distance_cross
        X = chaotic_population(
            ctx.rng, ctx.lower, ctx.upper, S * NP, map="logistic", mu=self.chaos_mu
        )
        F = ctx.evaluate(X)
        self.X = X.reshape(S, NP, D)
        self.F = F.reshape(S, NP)
        self.V = np.zeros_like(self.X)
        self.P = self.X.copy()
        self.Pf = self.F.copy()
        # Hosts: the best NP/5 food sources of each swarm's chaotic start (section 3.2.1).
        top = np.argsort(self.F, axis=1, kind="stable")[:, : self._no]
        s = np.arange(S)[:, None]
        self.O = self.X[s, top].copy()
        self.Of = self.F[s, top].copy()
        self.trial = np.zeros((S, self._no))

    def step(self, ctx: Context) -> None:
        rng = ctx.rng
        S, NP, NO, D = self.n_swarms, self._np, self._no, ctx.n_var
        lo, hi = ctx.lower, ctx.upper
        # Each particle picks a host by roulette on ABC fitness (eq. 2).
        choice = roulette_rows(rng, abc_fitness(self._scores(self.O, self.Of)), NP)
        s_idx = np.arange(S)[:, None]
        G = self.O[s_idx, choice]  # (S, NP, D): the host replaces gbest
        w = self.w_max - (self.w_max - self.w_min) * iteration_fraction(ctx)  # eq. 7
        r1 = rng.uniform(0.0, self.r_max, self.X.shape)
        r2 = rng.uniform(0.0, self.r_max, self.X.shape)
        V = w * self.V + r1 * (self.P - self.X) + r2 * (G - self.X)  # eq. 5
        self.V = np.clip(V, -self._vmax, self._vmax)
        self.X = clip_to_bounds(self.X + self.V, lo, hi)  # eq. 6
        self.F = ctx.evaluate(self.X.reshape(-1, D)).reshape(S, NP)
        better = self._scores(self.X, self.F) < self._scores(self.P, self.Pf)
        self.P[better] = self.X[better]
        self.Pf[better] = self.F[better]

        # Host competition: the best particle on each host replaces it when better.
        gk = (s_idx * NO + choice).reshape(-1)
        Fr = self.F.reshape(-1)
        Ff = self._scores(self.X, self.F).reshape(-1)
        Os = self._scores(self.O, self.Of).reshape(-1)
        order = np.lexsort((Ff, gk))
        first = np.ones(order.size, dtype=bool)
        first[1:] = gk[order][1:] != gk[order][:-1]
        best_p = order[first]
        hosts = gk[best_p]
        Of = self.Of.reshape(-1).copy()
        Ofl = self.O.reshape(S * NO, D).copy()
        trial = self.trial.reshape(-1).copy()
        imp = Ff[best_p] < Os[hosts]
        Xf = self.X.reshape(-1, D)
        Ofl[hosts[imp]] = Xf[best_p[imp]]
        Of[hosts[imp]] = Fr[best_p[imp]]
        visits = np.bincount(gk, minlength=S * NO).astype(np.float64)
        keep = np.ones(S * NO, dtype=bool)
        keep[hosts[imp]] = False
        trial[~keep] = 0.0
        trial[keep] += visits[keep]
        # Nectar limit: abandoned hosts are re-sampled in the box (eq. 3), memory lost.
        dead = np.flatnonzero(trial > self._limit)
        if dead.size and not ctx.exhausted():
            Ofl[dead] = self._respawn(ctx, dead // NO, Ofl[dead])
            Of[dead] = ctx.evaluate(Ofl[dead])
            trial[dead] = 0.0
        self.O = Ofl.reshape(S, NO, D)
        self.Of = Of.reshape(S, NO)
        self.trial = trial.reshape(S, NO)

        if S > 1 and (ctx.iteration + 1) % self.exchange_interval == 0:
            self._exchange()

    def _scores(self, X: NDArray[np.float64], F: NDArray[np.float64]) -> NDArray[np.float64]:
        """The values swarms rank by, ``(S, m)``, for positions ``X (S, m, D)`` of objective
        values ``F (S, m)``: here the objective itself (a hook for the multimodal planner)."""
        return F

    def _respawn(
        self, ctx: Context, swarms: NDArray[np.intp], hosts: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """New positions ``(n, D)`` for abandoned hosts ``hosts (n, D)`` of ``swarms (n,)``:
        uniform in the box (eq. 3)."""
        return random_in_bounds(ctx.rng, ctx.lower, ctx.upper, len(hosts))

    def _exchange(self) -> None:
        """Algorithm 1: multi-swarm elite selection through the mixing pool."""
        S, NP = self.n_swarms, self._np
        ne = min(self.n_elites, NP)
        order = np.argsort(self.Pf, axis=1, kind="stable")
        s_idx = np.arange(S)[:, None]
        elite_idx = order[:, :ne]
        EX = self.P[s_idx, elite_idx].copy()  # (S, ne, D) the pool, before any replacement
        EF = self.Pf[s_idx, elite_idx].copy()
        worst_idx = order[:, NP - min(self.n_worst, NP) :]
        for s in range(S):
            others = [o for o in range(S) if o != s]
            fX = EX[others].reshape(-1, EX.shape[2])
            fF = EF[others].reshape(-1)
            c1 = np.asarray(self._cross(fX, EX[s]), dtype=np.float64).reshape(-1)
            pick = np.argsort(c1, kind="stable")[: min(self.n_cross, c1.size)]
            wX = self.P[s, worst_idx[s]]
            wF = self.Pf[s, worst_idx[s]]
            mX = np.concatenate([fX[pick], wX])
            mF = np.concatenate([fF[pick], wF])
            c2 = np.asarray(self._cross(mX, EX[s]), dtype=np.float64).reshape(-1)
            k = int(np.argmin(c2))
            tgt = int(order[s, -1])  # the particle with the worst memory
            self.X[s, tgt] = mX[k]
            self.F[s, tgt] = mF[k]
            self.V[s, tgt] = 0.0
            if mF[k] < self.Pf[s, tgt]:
                self.P[s, tgt] = mX[k]
                self.Pf[s, tgt] = mF[k]
