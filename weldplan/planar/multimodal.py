"""ParaPA's multimodal path planning: the best k mutually distinct paths from one run.

Ren, Gao, Shen, Li, Jiang, Sensors 23:1751, 2023 (``../shared/papers/003_*``), sections 4.3
(the cross function, eq. 17), 4.4 (multimodal planning, Algorithm 2: multi-path reverse
planning) and 3.2.3 (Algorithm 1, the multi-swarm elite selection), on the rotated-frame
segment encoding of sections 4.1-4.2 (:class:`~weldplan.planar.encodings.SegmentPathProblem`).

What "distinct" means here
--------------------------
003 wants the k paths as alternatives: "when an emergency occurs on a path, the potential
solution can be immediately changed to another option" (section 4.4), and "segments of the
robot should not intersect with obstacles or any other potential solution" (section 4.3). Two
paths that run side by side through the same gap share any blockage of that gap, so a small
geometric distance is not enough. We therefore call two collision-free paths **distinct when
they pass at least one obstacle on different sides**: they lie in different *homology classes*
of the plane minus the obstacles. Exactly: the closed loop ``a`` followed by ``b`` reversed has
a non-zero winding number around a reference point inside at least one obstacle
(:func:`reference_points`). The winding numbers come from the angles each path sweeps around
each reference point (:func:`swept_angles`): for paths with the same ends the difference of the
sweeps is ``2 pi`` times the loop's winding number, so the test is exact (no tolerance beyond
rounding a multiple of ``2 pi``). Homology is coarser than homotopy (two paths that differ by a
commutator loop round two obstacles count as one class); it is used because it is exact and
cheap to test for a whole population. Distinct paths may share stretches (near the start,
say), where one blockage stops both; the pairwise segment-crossing count of eq. 17 and a
sampled Hausdorff distance are reported beside, for information.

How the swarms are pushed apart
-------------------------------
* **Cross function (eq. 17).** :func:`crossing_cross` counts, for each candidate path, the
  pairs (segment n of the candidate, segment of elite e) that touch, summed over the elites
  (``sum_e sum_n Cp_n^e``); touching at the common start or goal does not count. It follows
  the contract of :mod:`weldplan.optim.algorithms.parapa` (``cross(candidates (m, n),
  elites (E, n)) -> (m,)``, lower is better).
* **Algorithm 1, multimodal reading** (:meth:`MultimodalParaPA._exchange`). Section 4.3:
  "the cross evaluation should go through the sub-swarms except for the current swarm ...
  only the elite with the lowest number of segment intersections will be selected and mixed
  again with the worst individuals in each group memory ... the elite who has the greatest
  difference from others in the mixed group is selected in the next iteration." For swarm
  ``s`` the candidates are its own ``n_elites`` best memories, judged by the cross function
  against the *other* swarms' elites (their best memories); the ``n_cross`` least crossing
  are mixed with ``s``'s ``n_worst`` worst memories, judged again, and the least crossing
  replaces ``s``'s worst particle. (The single-best ParaPA imports foreign elites instead,
  which would pull the swarms onto one path.)
* **Class penalty (our addition, named deviation).** Crossing counts alone cannot separate
  classes: two paths side by side in one corridor cross zero times. So for ``k >= 2`` each
  swarm ranks by tiers (:meth:`MultimodalParaPA._scores`): (0) collision-free paths in a class
  of their own, (1) colliding paths in a class of their own, (2) paths in the class of the
  elite of a swarm of higher priority. The priority is rebuilt greedily whenever the
  memories change: the swarm with the best elite is free, the next best must avoid its class,
  and so on (:meth:`MultimodalParaPA._elite_sweeps`; a fixed order by swarm index left swarms
  stuck colliding in a class another swarm held collision-free). Colliding paths rank
  above duplicates on purpose: a path moves to another class only by passing through an
  obstacle, so the colliding paths on the way must be acceptable (with duplicates ranked
  second, map20-1 seed 0 ended with two of its three paths in one class). Tier 2 adds a
  multiple of the encoding's offset ``B`` that lifts it above every colliding value; the
  evaluation budget and the objective are untouched; with ``k = 1`` there is no penalty.
  (A colliding path's class is still defined: only a path through a reference point itself
  has none.)

The k paths are picked from the swarms' elites (each swarm's ``n_elites`` best memories):
shortest collision-free first, then greedily every next one distinct from all picked. Fewer
than k distinct collision-free paths leave the rest filled with the best remaining ones
(repeated when the elites hold fewer than k solutions), flagged (``success``, the
``distinct`` matrix) rather than hidden.

Multi-path reverse planning (Algorithm 2)
-----------------------------------------
:func:`reverse_repair`. 003 section 4.4: "normally, there are one or two segments that are
infeasible ... If the replaced nectar source only has one or two infeasible segments, the
reverse planning strategy is triggered": (1) find the infeasible segment ``S_i``; (2) go through
the pbest group (read as the personal bests of all swarms: the multimodal swarms each sit
in their own class, so a swarm's own memories rarely hold a free prefix where its elite
collides); if a memory has ``S_i`` feasible and every segment from ``S_i`` back to the
start feasible, its nodes replace the corresponding nodes of the nectar; else the nectar is
generated at random. Readings: with two infeasible segments ``S_i`` is the later one (so the
replaced prefix covers both); "the corresponding nodes" are the nodes of ``S_1 .. S_i`` (in the
rotated frame the inner nodes are the variables, so the prefix of variables is copied); the
memories are tried best first and one is accepted only when the whole repaired path is
collision-free (the junction segment after ``S_i`` is new; the paper's steps leave that check
implicit, its output is "new feasible paths"). It runs where the paper puts it, on the hosts
abandoned at the nectar limit (:meth:`MultimodalParaPA._respawn`; a repaired host costs one
evaluation, like a random one), and once more on the elites the k paths are picked from.
Both counts are in the result.
"""

from __future__ import annotations

import json
import logging
import math
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import WeldplanError
from weldplan.geometry.obstacles2d import Obstacles2D, _segments_touch
from weldplan.optim.algorithms.parapa import CrossFunction, ParaPA
from weldplan.optim.core import Context, minimize
from weldplan.optim.operators import random_in_bounds
from weldplan.planar.encodings import SegmentPathProblem
from weldplan.planar.scenarios import Scenario
from weldplan.random import RNGLike, seed_of

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: 003 section 5.2: NP = 50 particles per swarm, 200 evolutions
PAPER_NP = 50
PAPER_ITERATIONS = 200
#: swarms: 003 does not state the number (its Figure 9 shows k = 3 paths); one spare swarm
DEFAULT_SWARMS = 4
#: 003 section 4.4: reverse planning is triggered for at most this many infeasible segments
MAX_REPAIR_SEGMENTS = 2

#: points per path for the sampled Hausdorff distance (reported, not used for decisions)
HAUSDORFF_SAMPLES = 200


# ----------------------------------------------------------------------------- geometry
def reference_points(obstacles: Obstacles2D) -> FloatArray:
    """One point strictly inside each obstacle, ``(O, 2)``: circle and rectangle centres, and
    for a polygon the midpoint of the first interior stretch of a horizontal line through it
    (at a height between two vertex heights, so it meets no vertex; works for concave ones)."""
    pts = [
        obstacles.circles[:, :2],
        0.5 * (obstacles.rectangles[:, :2] + obstacles.rectangles[:, 2:]),
    ]
    poly = []
    for p in obstacles.polygons:
        ys = np.unique(p[:, 1])
        y = 0.5 * (ys[len(ys) // 2 - 1] + ys[len(ys) // 2]) if len(ys) > 1 else ys[0]
        a, b = p, np.roll(p, -1, axis=0)
        cross = (a[:, 1] > y) != (b[:, 1] > y)
        xs = a[cross, 0] + (y - a[cross, 1]) * (b[cross, 0] - a[cross, 0]) / (
            b[cross, 1] - a[cross, 1]
        )
        xs = np.sort(xs)
        poly.append([0.5 * (xs[0] + xs[1]), y])
    if poly:
        pts.append(np.asarray(poly, dtype=np.float64))
    return np.concatenate(pts).reshape(-1, 2)


def swept_angles(paths: ArrayLike, points: ArrayLike) -> FloatArray:
    """Angle (radians, signed) that the vector from each point to a traveller sweeps while
    the traveller follows each path: ``paths (..., n, 2)``, ``points (O, 2)`` -> ``(..., O)``.

    For two paths with the same ends, ``(sweep_a - sweep_b) / (2 pi)`` is the winding number
    of the loop ``a`` then ``b`` reversed around the point (an integer up to rounding)."""
    P = np.asarray(paths, dtype=np.float64)
    Q = np.asarray(points, dtype=np.float64)
    d = P[..., :, None, :] - Q  # (..., n, O, 2)
    step = np.diff(np.arctan2(d[..., 1], d[..., 0]), axis=-2)
    # each segment turns the vector by less than pi (unless it passes through the point)
    return np.sum((step + np.pi) % (2.0 * np.pi) - np.pi, axis=-2)


def class_differs(sweep_a: ArrayLike, sweep_b: ArrayLike) -> NDArray[np.bool_]:
    """Whether paths of sweeps ``(..., O)`` lie in different homology classes (broadcasting):
    some obstacle has a non-zero winding number of the loop between them."""
    d = (np.asarray(sweep_a) - np.asarray(sweep_b)) / (2.0 * math.pi)
    return np.any(np.rint(d) != 0, axis=-1)


def path_crossings(A: ArrayLike, B: ArrayLike) -> NDArray[np.int64]:
    """Eq. 17's cross values: for polylines ``A (m, n, 2)`` and ``B (E, p, 2)`` with the same
    start and goal, the number of (segment of a, segment of b) pairs that touch, ``(m, E)``.

    The first segments always touch at the common start and the last at the common goal;
    those two pairs are not counted. Identical paths count about three per segment."""
    A = np.asarray(A, dtype=np.float64)
    B = np.asarray(B, dtype=np.float64)
    a0, a1 = A[:, None, :-1, None, :], A[:, None, 1:, None, :]
    b0, b1 = B[None, :, None, :-1, :], B[None, :, None, 1:, :]
    touch = _segments_touch(a0, a1, b0, b1)  # (m, E, n - 1, p - 1)
    count = touch.sum(axis=(2, 3)).astype(np.int64)
    same_start = np.all(A[:, None, 0] == B[None, :, 0], axis=-1)
    same_goal = np.all(A[:, None, -1] == B[None, :, -1], axis=-1)
    return count - same_start - same_goal


def hausdorff(a: ArrayLike, b: ArrayLike, samples: int = HAUSDORFF_SAMPLES) -> float:
    """Symmetric Hausdorff distance between two polylines sampled at ``samples`` points each
    by arc length (map units; reported, not used for decisions)."""
    pa, pb = _resample(np.asarray(a, float), samples), _resample(np.asarray(b, float), samples)
    d = np.linalg.norm(pa[:, None] - pb[None], axis=-1)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def _resample(p: FloatArray, n: int) -> FloatArray:
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    t = np.linspace(0.0, s[-1], n)
    return np.stack([np.interp(t, s, p[:, 0]), np.interp(t, s, p[:, 1])], axis=1)


def crossing_cross(problem: SegmentPathProblem) -> CrossFunction:
    """Eq. 17 as a ParaPA cross function on ``problem``'s variables: for each candidate the
    crossings (:func:`path_crossings`) with all the elites summed, ``(m,) float``."""

    def cross(candidates: FloatArray, elites: FloatArray) -> FloatArray:
        c = path_crossings(problem.decode(candidates), problem.decode(elites))
        return c.sum(axis=1).astype(np.float64)

    return cross


# ---------------------------------------------------------------------- reverse planning
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


# -------------------------------------------------------------------------------- result
@dataclass(frozen=True)
class MultimodalResult:
    """The k paths of one multimodal run (:func:`plan_multimodal`).

    Attributes
    ----------
    scenario
        Scenario name.
    k
        Paths asked for.
    paths
        ``k`` polylines ``((n, 2))`` from start to goal, shortest first among the distinct
        collision-free ones.
    lengths
        Their lengths (map units).
    success
        Whether each is collision-free (exact segment check).
    swarm
        The swarm whose elite each path is.
    distinct
        ``k x k``: whether paths i and j lie in different homology classes (the diagonal is
        ``False``).
    crossings
        ``k x k``: eq. 17 cross values between the paths (touching segment pairs).
    hausdorff
        ``k x k``: sampled Hausdorff distances (map units).
    optimum
        The exact shortest path's length (visibility graph; ``nan`` when not computed).
    repairs
        Abandoned hosts repaired by Algorithm 2 during the run.
    final_repairs
        Elites repaired by Algorithm 2 when the k paths were picked.
    n_swarms, pop_per_swarm, iterations
        The run's settings.
    n_eval, seconds, seed
        Evaluations spent by the run (the final repairs evaluate at most ``n_swarms x
        n_elites`` more, outside the budget), wall time of the run and the selection, seed.
    """

    scenario: str
    k: int
    paths: tuple[tuple[tuple[float, float], ...], ...]
    lengths: tuple[float, ...]
    success: tuple[bool, ...]
    swarm: tuple[int, ...]
    distinct: tuple[tuple[bool, ...], ...]
    crossings: tuple[tuple[int, ...], ...]
    hausdorff: tuple[tuple[float, ...], ...]
    optimum: float
    repairs: int
    final_repairs: int
    n_swarms: int
    pop_per_swarm: int
    iterations: int
    n_eval: int
    seconds: float
    seed: int | None = None

    @property
    def gaps(self) -> tuple[float, ...]:
        """Each path's relative excess over the exact optimum (0.02 = 2 % longer)."""
        return tuple(L / self.optimum - 1.0 for L in self.lengths)

    @property
    def n_success(self) -> int:
        return int(sum(self.success))

    @property
    def all_distinct(self) -> bool:
        """Every pair of paths distinct (vacuously true for k = 1)."""
        k = len(self.paths)
        return all(self.distinct[i][j] for i in range(k) for j in range(k) if i != j)

    def path_array(self, i: int) -> FloatArray:
        return np.asarray(self.paths[i], dtype=np.float64).reshape(-1, 2)

    def to_json(self) -> str:
        return json.dumps(asdict(self), allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> MultimodalResult:
        d = json.loads(text)
        d["paths"] = tuple(tuple(tuple(p) for p in path) for path in d["paths"])
        for key in ("lengths", "success", "swarm"):
            d[key] = tuple(d[key])
        for key in ("distinct", "crossings", "hausdorff"):
            d[key] = tuple(tuple(row) for row in d[key])
        return cls(**d)


# ----------------------------------------------------------------------------- planning
def check_k(k: int, n_swarms: int) -> None:
    """Raise a :class:`WeldplanError` naming the option when ``k`` cannot be served."""
    if n_swarms < 1:
        raise WeldplanError(f"the number of swarms must be >= 1 (option --swarms), got {n_swarms}")
    if k < 1:
        raise WeldplanError(f"k must be at least 1 (option --k), got {k}")
    if k > n_swarms:
        raise WeldplanError(
            f"k = {k} is more than the {n_swarms} swarms: each path is a swarm's elite "
            "(option --k; or raise --swarms)"
        )


def plan_multimodal(
    scenario: Scenario,
    k: int = 3,
    *,
    n_swarms: int = DEFAULT_SWARMS,
    pop_per_swarm: int = PAPER_NP,
    iterations: int = PAPER_ITERATIONS,
    n_nodes: int | None = None,
    repair: bool = True,
    rng: RNGLike = None,
    with_optimum: bool = True,
    optimizer_params: dict[str, Any] | None = None,
) -> MultimodalResult:
    """Plan the best ``k`` mutually distinct collision-free paths in one ParaPA run.

    Parameters
    ----------
    scenario
        The map (any obstacles); planned in 003's rotated frame with ``n_nodes`` inner nodes
        (default: the scenario's).
    k
        Paths wanted, ``1 <= k <= n_swarms``.
    n_swarms, pop_per_swarm, iterations
        Swarms (not stated in 003; 4, one spare), particles per swarm (003 section 5.2:
        NP = 50) and iterations (200).
    repair
        Multi-path reverse planning (Algorithm 2) on abandoned hosts and on the elites.
    rng
        Seed or Generator.
    with_optimum
        Compute the exact shortest path (visibility graph) for the gaps.
    optimizer_params
        Further :class:`~weldplan.optim.algorithms.parapa.ParaPA` settings.

    Raises
    ------
    WeldplanError
        ``k < 1`` or ``k > n_swarms``.
    """
    check_k(int(k), int(n_swarms))
    if pop_per_swarm < 1 or iterations < 1:
        raise WeldplanError(
            "pop_per_swarm and iterations must be >= 1 (options --pop, --iterations)"
        )
    problem = SegmentPathProblem(scenario, n_nodes=n_nodes)
    opt = MultimodalParaPA(
        problem,
        k,
        repair=repair,
        n_swarms=n_swarms,
        pop_size=n_swarms * pop_per_swarm,
        **(optimizer_params or {}),
    )
    t0 = time.perf_counter()
    res = minimize(problem, opt, max_iter=iterations, rng=rng)
    picked, final_repairs = _pick(problem, opt, k)
    seconds = time.perf_counter() - t0
    paths = [problem.path(x) for _, x in picked]
    ok = [bool(v) for v in problem.success(np.array([x for _, x in picked]))]
    sweeps = swept_angles(np.stack(paths), reference_points(scenario.obstacles))
    n = len(paths)
    distinct = [
        [bool(i != j and class_differs(sweeps[i], sweeps[j])) for j in range(n)] for i in range(n)
    ]
    cross = path_crossings(np.stack(paths), np.stack(paths))
    for i in range(n):
        cross[i, i] = 0
    haus = [[0.0 if i == j else hausdorff(paths[i], paths[j]) for j in range(n)] for i in range(n)]
    optimum = float("nan")
    if with_optimum:
        from weldplan.planar.solve import exact_optimum

        optimum = exact_optimum(scenario, "segments").length
    log.info(
        "multimodal %s: k=%d, %d collision-free, %d repairs in the run, %d at the end",
        scenario.name,
        k,
        sum(ok),
        opt.repairs,
        final_repairs,
    )
    return MultimodalResult(
        scenario=scenario.name,
        k=int(k),
        paths=tuple(tuple((float(a), float(b)) for a, b in p) for p in paths),
        lengths=tuple(float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))) for p in paths),
        success=tuple(ok),
        swarm=tuple(int(s) for s, _ in picked),
        distinct=tuple(tuple(r) for r in distinct),
        crossings=tuple(tuple(int(v) for v in r) for r in cross),
        hausdorff=tuple(tuple(r) for r in haus),
        optimum=optimum,
        repairs=opt.repairs,
        final_repairs=final_repairs,
        n_swarms=int(n_swarms),
        pop_per_swarm=int(pop_per_swarm),
        iterations=res.n_iter,
        n_eval=res.n_eval,
        seconds=seconds,
        seed=seed_of(rng),
    )


def _pick(
    problem: SegmentPathProblem, opt: MultimodalParaPA, k: int
) -> tuple[list[tuple[int, FloatArray]], int]:
    """The k paths from the swarms' elites (module docstring): ``[(swarm, x)]`` and the
    number of elites repaired by Algorithm 2."""
    S, NP = opt.n_swarms, opt._np
    ne = min(opt.n_elites, NP)
    Ps = opt._scores(opt.P, opt.Pf)
    order = np.argsort(Ps, axis=1, kind="stable")[:, :ne]
    swarm = np.repeat(np.arange(S), ne)
    X = opt.P[swarm, order.reshape(-1)].copy()
    F = opt.Pf[swarm, order.reshape(-1)].copy()
    repaired = 0
    if opt.repair:
        group, group_f = opt.P.reshape(-1, opt.P.shape[-1]), opt.Pf.reshape(-1)
        group_bad = infeasible_segments(problem, group)
        for j in np.flatnonzero(F >= problem.offset):
            fixed = reverse_repair(
                problem, X[j], group, memory_fitness=group_f, memory_infeasible=group_bad
            )
            if fixed is not None:
                X[j] = fixed
                F[j] = problem.evaluate(fixed[None])[0]
                repaired += 1
    # unique solutions, collision-free and shortest first
    _, first = np.unique(X, axis=0, return_index=True)
    keep = np.sort(first)
    X, F, swarm = X[keep], F[keep], swarm[keep]
    ok = problem.success(X)
    rank = np.lexsort((F, ~ok))
    sweep = swept_angles(problem.decode(X), opt.refs)
    chosen: list[int] = []
    for j in rank:
        if not ok[j]:
            break
        if all(class_differs(sweep[j], sweep[c]) for c in chosen):
            chosen.append(int(j))
        if len(chosen) == k:
            break
    for j in rank:  # fewer than k distinct collision-free paths: fill with the best left
        if len(chosen) == k:
            break
        if int(j) not in chosen:
            chosen.append(int(j))
    while len(chosen) < k:  # the swarms' elites collapsed onto fewer than k solutions
        chosen.append(chosen[-1])
    return [(int(swarm[j]), X[j]) for j in chosen], repaired
