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
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import WeldplanError
from weldplan.optim.core import minimize
from weldplan.planar.encodings import SegmentPathProblem
from weldplan.planar.homology import (  # noqa: F401 - re-exported
    HAUSDORFF_SAMPLES,
    class_differs,
    crossing_cross,
    hausdorff,
    path_crossings,
    reference_points,
    swept_angles,
)
from weldplan.planar.multimodal_optimizer import (  # noqa: F401 - re-exported
    DEFAULT_SWARMS,
    MAX_REPAIR_SEGMENTS,
    PAPER_ITERATIONS,
    PAPER_NP,
    MultimodalParaPA,
    infeasible_segments,
    reverse_repair,
)
from weldplan.planar.scenarios import Scenario
from weldplan.random import RNGLike, seed_of

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]


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
    distinct, cross, haus = pairwise_measures(paths, scenario.obstacles)
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
        distinct=distinct,
        crossings=cross,
        hausdorff=haus,
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


def pairwise_measures(paths: list[FloatArray], obstacles: Any) -> tuple[Any, Any, Any]:
    """How the paths ``(n_i, 2)`` (same ends) differ, pair by pair, as :class:`MultimodalResult`
    keeps it: ``distinct`` (different homology classes round ``obstacles``,
    :func:`class_differs`), eq. 17's segment ``crossings`` (zero on the diagonal) and the
    sampled ``hausdorff`` distance; each ``(n, n)`` as nested tuples of bool, int, float."""
    sweeps = swept_angles(np.stack(paths), reference_points(obstacles))
    n = len(paths)
    distinct = [
        [bool(i != j and class_differs(sweeps[i], sweeps[j])) for j in range(n)] for i in range(n)
    ]
    cross = path_crossings(np.stack(paths), np.stack(paths))
    for i in range(n):
        cross[i, i] = 0
    haus = [[0.0 if i == j else hausdorff(paths[i], paths[j]) for j in range(n)] for i in range(n)]
    return (
        tuple(tuple(r) for r in distinct),
        tuple(tuple(int(v) for v in r) for r in cross),
        tuple(tuple(r) for r in haus),
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
