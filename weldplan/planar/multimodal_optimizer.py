"""The optimiser of ParaPA's multimodal planning (paper 003): :class:`MultimodalParaPA`, whose
swarms settle on mutually distinct paths, and the multi-path reverse planning of Algorithm 2
(:func:`reverse_repair`). :mod:`weldplan.planar.multimodal`'s docstring gives the method, the
readings of the paper and the deviations.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.optim.algorithms.parapa import ParaPA
from weldplan.optim.core import Context
from weldplan.optim.operators import random_in_bounds
from weldplan.planar.encodings import SegmentPathProblem
from weldplan.planar.homology import (
    class_differs,
    crossing_cross,
    path_crossings,
    reference_points,
    swept_angles,
)

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: 003 section 5.2: NP = 50 particles per swarm, 200 evolutions
PAPER_NP = 50
PAPER_ITERATIONS = 200
#: swarms: 003 does not state the number (its Figure 9 shows k = 3 paths); one spare swarm
DEFAULT_SWARMS = 4
#: 003 section 4.4: reverse planning is triggered for at most this many infeasible segments
MAX_REPAIR_SEGMENTS = 2


def infeasible_segments(problem: SegmentPathProblem, X: ArrayLike) -> NDArray[np.bool_]:
    """Which segments of each solution's path collide: ``X (m, n_var)`` -> ``(m, N) bool``."""
    P = problem.decode(np.atleast_2d(np.asarray(X, dtype=np.float64)))
    return problem.world.segments_hit(P[:, :-1], P[:, 1:])


def reverse_repair(
    problem: SegmentPathProblem,
    x: ArrayLike,
    memories: ArrayLike,
    *,
    max_segments: int = MAX_REPAIR_SEGMENTS,
    memory_fitness: ArrayLike | None = None,
    memory_infeasible: NDArray[np.bool_] | None = None,
) -> FloatArray | None:
    """003 Algorithm 2 (multi-path reverse planning) on one path; ``None`` when it does not
    apply or finds nothing (the caller then generates the nectar at random, as 003 does).

    Parameters
    ----------
    problem
        The rotated-frame encoding (inner node i is variable i - 1).
    x
        ``(n_var,)`` the path to repair; only paths with 1 to ``max_segments`` infeasible
        segments are repaired.
    memories
        ``(M, n_var)`` the personal-best group.
    memory_fitness
        ``(M,)`` optional: the memories are tried in increasing order (else in their order).
    memory_infeasible
        ``(M, N) bool`` optional: :func:`infeasible_segments` of the memories, when the
        caller repairs several paths from one group.

    Returns
    -------
    ``(n_var,)`` the repaired solution (collision-free), or ``None``.
    """
    x = np.asarray(x, dtype=np.float64).reshape(-1)
    M = np.atleast_2d(np.asarray(memories, dtype=np.float64))
    bad = infeasible_segments(problem, x[None])[0]  # (N,)
    nbad = int(bad.sum())
    if nbad == 0 or nbad > max_segments or len(M) == 0:
        return None
    i = int(np.flatnonzero(bad)[-1])  # S_i (0-based segment i: node i -> node i + 1)
    mb = infeasible_segments(problem, M) if memory_infeasible is None else memory_infeasible
    ok = ~np.any(mb[:, : i + 1], axis=1)  # S_i and every segment back to the start feasible
    if memory_fitness is not None:
        order = np.argsort(np.asarray(memory_fitness, dtype=np.float64), kind="stable")
        ok_idx = order[ok[order]]
    else:
        ok_idx = np.flatnonzero(ok)
    if not len(ok_idx):
        return None
    # the nodes of S_1 .. S_i are nodes 1 .. i + 1 (node 0 is the start): variables 0 .. i
    cand = np.repeat(x[None], len(ok_idx), axis=0)
    n = min(i + 1, problem.n_var)
    cand[:, :n] = M[ok_idx, :n]
    good = ~np.any(infeasible_segments(problem, cand), axis=1)
    if not good.any():
        return None
    return cand[int(np.argmax(good))]


# ----------------------------------------------------------------------------- optimiser
class MultimodalParaPA(ParaPA):
    """ParaPA whose swarms settle on mutually distinct paths (see the module docstring).

    Parameters
    ----------
    problem
        The rotated-frame segment encoding the run minimises (the optimiser decodes paths to
        count crossings, classify them and repair them).
    k
        Paths wanted; ``k >= 2`` switches the class penalty on.
    repair
        Run Algorithm 2 on abandoned hosts (003 section 4.4).
    **params
        :class:`~weldplan.optim.algorithms.parapa.ParaPA` settings (``pop_size`` is the total
        over ``n_swarms``).
    """

    name = "parapa-multimodal"

    def __init__(
        self,
        problem: SegmentPathProblem,
        k: int = 3,
        *,
        repair: bool = True,
        **params: Any,
    ) -> None:
        params.setdefault("n_swarms", DEFAULT_SWARMS)
        params.setdefault("pop_size", PAPER_NP * params["n_swarms"])
        super().__init__(cross=crossing_cross(problem), **params)
        self.problem = problem
        self.k = int(k)
        self.repair = bool(repair)
        self.refs = reference_points(problem.scenario.obstacles)
        self.repairs = 0
        self.random_respawns = 0
        # colliding values of the encoding are B (1 + f3 + f4) + w f1 with f3, f4 <= 1 and
        # f1 <= B: below (3 + w) B, so this shift puts tier 2 behind all of them
        self._dup_shift = (4.0 + max(problem.w, 0.0)) * problem.offset

    # -- ranking -------------------------------------------------------------------------
    def initialize(self, ctx: Context) -> None:
        self._cache: dict[bytes, Any] = {}
        super().initialize(ctx)

    def _sweeps(self, X: FloatArray) -> FloatArray:
        """:func:`swept_angles` of positions ``X (..., D)`` -> ``(..., O)``, cached (ranking
        asks for the same memories several times an iteration)."""
        key = b"s" + X.tobytes()
        out = self._cache.get(key)
        if out is None:
            if len(self._cache) > 16:
                self._cache.clear()
            D = X.shape[-1]
            out = swept_angles(self.problem.decode(X.reshape(-1, D)), self.refs)
            out = out.reshape(*X.shape[:-1], -1)
            self._cache[key] = out
        return out

    def _elite_sweeps(self) -> list[FloatArray | None]:
        """For each swarm, the sweeps ``(R, O)`` of the collision-free elites of the swarms
        ranked before it (``None`` when there are none).

        The priority is rebuilt greedily each time: the swarm whose best memory (ranked with
        the classes taken so far) is best goes next, and its elite's class is taken when it
        is collision-free. A swarm stuck colliding in a class that another swarm holds
        collision-free is thus pushed out of it."""
        key = b"e" + self.P.tobytes() + self.Pf.tobytes()
        out = self._cache.get(key)
        if out is not None:
            return out
        sweep = self._sweeps(self.P)
        feasible = self.Pf < self.problem.offset
        out = [None] * self.n_swarms
        refs: list[FloatArray] = []
        left = list(range(self.n_swarms))
        while left:
            taken = np.stack(refs) if refs else None
            best = None
            for s in left:
                tier = self._tier_of(sweep[s], feasible[s], taken)
                e = int(np.lexsort((self.Pf[s], tier))[0])
                rank = (int(tier[e]), float(self.Pf[s, e]))
                if best is None or rank < best[0]:
                    best = (rank, s, e)
            assert best is not None
            (tier_e, _), s, e = best
            out[s] = taken
            if tier_e <= 1:  # a class is held by one swarm, even while its elite collides
                refs.append(sweep[s, e])
            left.remove(s)
        self._cache[key] = out
        return out

    @staticmethod
    def _tier_of(
        sweep: FloatArray, feasible: NDArray[np.bool_], refs: FloatArray | None
    ) -> NDArray[np.int64]:
        """0: collision-free, in a class of its own; 1: colliding, in a class of its own;
        2: in the class of one of ``refs`` (the elites of higher-priority swarms)."""
        tier = np.where(feasible, 0, 1)
        if refs is not None:
            dup = np.any(~class_differs(sweep[:, None, :], refs[None]), axis=1)
            tier = np.where(dup, 2, tier)
        return tier

    def _scores(self, X: FloatArray, F: FloatArray) -> FloatArray:
        """Tiered values (:meth:`_tier_of`): ``F`` for tiers 0 and 1 (colliding values already
        exceed the encoding's offset ``B``), ``F + (4 + w) B`` for tier 2, behind every
        colliding value."""
        if self.k < 2 or self.n_swarms < 2:
            return F
        sweep = self._sweeps(X)
        feasible = F < self.problem.offset
        out = F.copy()
        for s, refs in enumerate(self._elite_sweeps()):
            if refs is not None:
                tier = self._tier_of(sweep[s], feasible[s], refs)
                out[s] = np.where(tier == 2, F[s] + self._dup_shift, F[s])
        return out

    # -- reverse planning ------------------------------------------------------------------
    def _respawn(self, ctx: Context, swarms: NDArray[np.intp], hosts: FloatArray) -> FloatArray:
        """Abandoned hosts: Algorithm 2 from the personal bests of all swarms, else uniform
        (eq. 3)."""
        new = random_in_bounds(ctx.rng, ctx.lower, ctx.upper, len(hosts))
        if not self.repair:
            self.random_respawns += len(hosts)
            return new
        D = self.P.shape[-1]
        group, group_f = self.P.reshape(-1, D), self.Pf.reshape(-1)
        group_bad = infeasible_segments(self.problem, group)
        for j, h in enumerate(hosts):
            fixed = reverse_repair(
                self.problem, h, group, memory_fitness=group_f, memory_infeasible=group_bad
            )
            if fixed is None:
                self.random_respawns += 1
            else:
                new[j] = fixed
                self.repairs += 1
        return new

    # -- Algorithm 1, multimodal reading -----------------------------------------------------
    def _exchange(self) -> None:
        """Algorithm 1 with section 4.3's reading (module docstring). The eq. 17 values of all
        memories against every swarm's elite come from one :func:`path_crossings` call; a
        candidate's cross value for swarm ``s`` sums the columns of the other swarms."""
        S, NP = self.n_swarms, self._np
        ne = min(self.n_elites, NP)
        Ps = self._scores(self.P, self.Pf)
        order = np.argsort(Ps, axis=1, kind="stable")
        best = self.P[np.arange(S), order[:, 0]]  # (S, D): each swarm's elite in the pool
        nw = min(self.n_worst, NP)
        rows = np.concatenate([order[:, :ne], order[:, NP - nw :]], axis=1)  # (S, ne + nw)
        cand = self.P[np.arange(S)[:, None], rows]
        C = path_crossings(
            self.problem.decode(cand.reshape(-1, cand.shape[-1])), self.problem.decode(best)
        ).reshape(S, rows.shape[1], S)
        for s in range(S):
            cs = C[s].sum(axis=1) - C[s, :, s]  # against the other swarms' elites
            pick = np.argsort(cs[:ne], kind="stable")[: min(self.n_cross, ne)]
            mix = np.concatenate([pick, np.arange(ne, ne + nw)])  # + the worst memories
            src = int(rows[s, mix[int(np.argmin(cs[mix]))]])
            tgt = int(order[s, -1])  # the particle with the worst memory
            if src == tgt:
                continue
            self.X[s, tgt] = self.P[s, src]
            self.F[s, tgt] = self.Pf[s, src]
            self.V[s, tgt] = 0.0
            # "the replaced individuals always keep the best memories"
            if Ps[s, src] < Ps[s, tgt]:
                self.P[s, tgt] = self.P[s, src]
                self.Pf[s, tgt] = self.Pf[s, src]
