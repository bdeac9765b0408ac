"""One planar planning run end to end: scenario -> Problem -> optimiser -> measured path.

Used by ``weldplan planar`` and ``weldplan bench planar``; the optimiser sees only the Problem.

Two pipelines (:func:`solve`):

* the default, the best we measured (``docs/bench-planar.md``, "Default pipeline"): the
  optimiser seeded along a coarse A* roadmap (``init="problem"`` for the optimisers that take
  it: sma and lrsma; an improvement not in the papers) with the budgets of
  :data:`DEFAULT_BUDGET`, then the stages of :mod:`weldplan.planar.pipeline` (repair of
  colliding stretches, polish to a taut path), compared with the exact any-angle optimum;
* ``as_printed=True``: the paper's algorithm alone, with the paper's budget
  (:data:`PAPER_BUDGET`) and initialisation, compared with the encoding's exact baseline (as
  ``weldplan bench planar`` reproduces the papers' tables).
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any, TypedDict, Unpack

import numpy as np

from weldplan.errors import ConfigError
from weldplan.geometry.pathcore import at_fractions
from weldplan.geometry.pathmetrics import measure
from weldplan.optim.core import minimize
from weldplan.optim.registry import get_optimizer
from weldplan.options import laid_over
from weldplan.planar.encodings import PathProblem, make_problem, population_diversity
from weldplan.planar.exact import ExactPath, astar_grid
from weldplan.planar.pipeline import PlanarStage, run_stages
from weldplan.planar.scenarios import Scenario
from weldplan.random import RNGLike, seed_of

log = logging.getLogger(__name__)

#: the papers' budgets per encoding: (population, iterations)
#: 000 Table 2: 30 x 30; 003 sec. 5.2: NP = 50, 200 evolutions; 001: N = 50 fish
#: (its iteration count is not given; 100 here)
PAPER_BUDGET: dict[str, tuple[int, int]] = {
    "spline": (30, 30),
    "segments": (50, 200),
    "grid": (50, 100),
}

#: the optimiser of ``weldplan planar`` when none is named (paper 000's LRSMA)
DEFAULT_ALGORITHM = "lrsma"

#: the default pipeline's budgets: the repair and polish stages leave the optimiser only the
#: choice of a corridor, which the seeded segment encoding finds within 30 x 60 (measured in
#: docs/bench-planar.md); the paper's 50 x 200 costs 2-14 s a run on this machine
DEFAULT_BUDGET: dict[str, tuple[int, int]] = {
    "spline": (30, 30),
    "segments": (30, 60),
    "grid": (50, 100),
}

_EXACT_CACHE: dict[tuple[str, str, str], ExactPath] = {}


def exact_optimum(scenario: Scenario, encoding: str | None = None) -> ExactPath:
    """The exact baseline of a scenario: the any-angle shortest path by Polyanya on the
    scenario's navigation mesh (:mod:`weldplan.planar.anyangle`: circles as the visibility
    graph's circumscribed ``CIRCLE_SIDES``-gons, so the lengths equal the visibility graph's,
    which the tests check on every bundled scenario), or for the grid encoding the 8-connected
    A* path (in map units, through cell centres). Cached per scenario file."""
    enc = encoding or scenario.encoding
    key = (str(scenario.path), scenario.name, "grid" if enc == "grid" else "any")
    if key in _EXACT_CACHE:
        return _EXACT_CACHE[key]
    if enc == "grid" and scenario.grid is not None:
        g = scenario.grid
        s = tuple(int(v) for v in g.cell_of(scenario.start))
        t = tuple(int(v) for v in g.cell_of(scenario.goal))
        r = astar_grid(~g.occupied, s, t)
        pts = g.centre(r.points_array.astype(np.int64))
        out = ExactPath(
            points=tuple((float(x), float(y)) for x, y in pts),
            length=r.length * g.cell,
            method=r.method,
            expanded=r.expanded,
        )
    else:
        from weldplan.planar.anyangle import polyanya_shortest_path, scenario_navmesh

        mesh = scenario_navmesh(scenario.obstacles, scenario.bounds)
        out = polyanya_shortest_path(mesh, scenario.start, scenario.goal)
    _EXACT_CACHE[key] = out
    return out


#: node placements (arc-length fractions of the exact path) that start the local searches of
#: :func:`spline_encoding_optimum`
_NODE_FRACTIONS = ((0.25, 0.5, 0.75), (0.2, 0.5, 0.8), (0.3, 0.5, 0.7), (0.15, 0.45, 0.8))


def spline_encoding_optimum(
    scenario: Scenario, *, n_jitter: int = 8, rng: RNGLike = 0, max_iter: int = 3000
) -> float:
    """The shortest collision-free path the spline encoding (paper 000, m = 3) was seen to reach.

    The exact optimum is a polyline; a cubic spline through three free nodes cannot follow
    its corners exactly, so ``exact_optimum`` is a lower bound the encoding may not attain.
    This is an upper bound of the encoding's own optimum: Nelder-Mead (scipy) on eq. 10 from
    nodes placed on the exact path at a few arc-length fractions (and ``n_jitter`` jittered
    placements, one restart each), the shortest path that :meth:`SplinePathProblem.success`
    accepts. Measured (defaults): circles-1 28.889 (exact 28.884), circles-2 28.925 (28.923),
    circles-3 29.620 (29.494); a multistart of 264 local searches (random and path-seeded
    starts) found circles-3 29.558 and nothing shorter on the other two.
    Cached per scenario file.
    """
    from scipy.optimize import minimize as nelder_mead

    from weldplan.random import as_generator

    key = (str(scenario.path), scenario.name, "spline-encoding")
    if key in _EXACT_CACHE:
        return _EXACT_CACHE[key].length
    prob = make_problem(scenario, "spline")
    pts = exact_optimum(scenario, "spline").points_array
    gen = as_generator(rng)
    m = prob.n_var // 2
    fracs = [
        np.asarray(f[:m] if len(f) >= m else np.linspace(0, 1, m + 2)[1:-1])
        for f in _NODE_FRACTIONS
    ]
    fracs += [np.sort(gen.uniform(0.05, 0.95, m)) for _ in range(n_jitter)]

    def f(x: np.ndarray) -> float:
        return float(prob.evaluate(x[None])[0])

    best = np.inf
    for q in fracs:
        x0 = at_fractions(pts, q)
        x = x0.ravel()
        for _ in range(2):  # one restart: Nelder-Mead's simplex collapses early on eq. 10
            opts = {"maxiter": max_iter, "xatol": 1e-7, "fatol": 1e-9}
            x = nelder_mead(f, x, method="Nelder-Mead", options=opts).x
        x = np.clip(x, prob.lower, prob.upper)
        if prob.success(x[None])[0]:
            best = min(best, prob.measure(x).length)
    _EXACT_CACHE[key] = ExactPath(points=(), length=float(best), method="spline-nelder-mead")
    return float(best)


@dataclass(frozen=True)
class PlanarRun:
    """The outcome of :func:`solve`.

    Attributes
    ----------
    scenario, algorithm, encoding
        What was run.
    points
        The best path's polyline.
    length, smoothness, min_clearance
        Its metrics (map units, radians).
    success
        Collision-free by the encoding's criterion (:meth:`PathProblem.success`; for splines
        paper 000's ``f2 = 0``).
    collisions
        Segments of the polyline that enter an obstacle (exact check).
    fitness
        The Problem's fitness of the best solution.
    optimum
        Exact baseline length (``nan`` when not computed).
    seconds
        Optimiser wall time (the run itself, not the exact baseline).
    n_eval, seed
        Evaluations spent, integer seed if given.
    history
        Best fitness after initialisation and each iteration.
    diversity
        Paper 003 eq. 18 of the final population when the optimiser keeps one in ``X``.
    pipeline
        ``"default"`` (optimiser, repair, polish) or ``"as-printed"`` (the paper's algorithm
        alone).
    stages
        The default pipeline's :class:`~weldplan.planar.pipeline.PlanarStage` records (the
        optimiser's own path first); empty as printed. ``points``, ``length``, ``collisions``
        and the other metrics are the final path's; ``success`` is then ``collisions == 0``.
    optimum_method
        How ``optimum`` was computed (the any-angle optimum for the default pipeline, the
        encoding's exact baseline as printed: octile A* for the grid encoding).
    """

    scenario: str
    algorithm: str
    encoding: str
    points: tuple[tuple[float, float], ...]
    length: float
    smoothness: float
    min_clearance: float
    success: bool
    collisions: int
    fitness: float
    optimum: float
    seconds: float
    n_eval: int
    seed: int | None
    history: tuple[float, ...]
    diversity: float = float("nan")
    pipeline: str = "as-printed"
    stages: tuple[PlanarStage, ...] = ()
    optimum_method: str = ""

    @property
    def gap(self) -> float:
        """Relative excess over the exact optimum (0.02 = 2 % longer)."""
        return self.length / self.optimum - 1.0

    def to_json(self) -> str:
        return json.dumps(asdict(self), allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> PlanarRun:
        d = json.loads(text)
        d["points"] = tuple(tuple(p) for p in d["points"])
        d["history"] = tuple(d["history"])
        d["stages"] = tuple(PlanarStage(**x) for x in d.get("stages", ()))
        return cls(**d)


@dataclass(frozen=True)
class PlanarSettings:
    """How :func:`solve` plans: one frozen, validated settings object (../shared/DESIGN.md: a
    stage takes its inputs and one settings object).

    Attributes
    ----------
    encoding
        ``"spline"``, ``"segments"`` or ``"grid"``; ``None``: the scenario's.
    pop_size, max_iter
        The optimiser's budget; ``None``: :data:`DEFAULT_BUDGET` (or :data:`PAPER_BUDGET` with
        ``as_printed``) for the encoding.
    with_optimum
        Compute the exact optimum beside the run (for its gap).
    encoding_params
        Keywords of the encoding's Problem (:func:`~weldplan.planar.encodings.make_problem`).
    optimizer_params
        The optimiser's parameters; ``init`` overrides the default pipeline's roadmap seeding.
    as_printed
        The paper's algorithm alone with the paper's budget (module docstring).
    """

    encoding: str | None = None
    pop_size: int | None = None
    max_iter: int | None = None
    with_optimum: bool = True
    encoding_params: Mapping[str, Any] | None = None
    optimizer_params: Mapping[str, Any] | None = None
    as_printed: bool = False

    def __post_init__(self) -> None:
        if self.encoding is not None and self.encoding not in PAPER_BUDGET:
            raise ConfigError(
                f"unknown encoding {self.encoding!r}; one of {', '.join(PAPER_BUDGET)}",
                field="encoding",
            )
        for name in ("pop_size", "max_iter"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or int(v) < 1):
                raise ConfigError(f"{name} must be >= 1, got {v!r}", field=name)


class PlanarOptions(TypedDict, total=False):
    """The keyword conveniences of :func:`solve`: any :class:`PlanarSettings` field by name."""

    encoding: str | None
    pop_size: int | None
    max_iter: int | None
    with_optimum: bool
    encoding_params: Mapping[str, Any] | None
    optimizer_params: Mapping[str, Any] | None
    as_printed: bool


def solve(
    scenario: Scenario,
    algorithm: str,
    settings: PlanarSettings | None = None,
    *,
    rng: RNGLike = None,
    problem: PathProblem | None = None,
    **options: Unpack[PlanarOptions],
) -> PlanarRun:
    """Plan a path on ``scenario`` with the registered ``algorithm``.

    By default the pipeline of the module docstring: roadmap-seeded optimiser (budgets of
    :data:`DEFAULT_BUDGET`), repair, polish; ``optimizer_params`` given ``init`` overrides the
    seeding. ``as_printed=True`` runs the paper's algorithm alone with the paper's budget
    (:data:`PAPER_BUDGET`): the same result, bit for bit, as before the pipeline existed.

    ``settings``: :class:`PlanarSettings` (encoding, budget, optimum, parameters, pipeline;
    ``None``: the defaults), any of its fields also by name in ``options`` (``pop_size=12``...),
    laid over it; ``problem``: a prebuilt Problem of the encoding (to share it between runs).
    """
    st = laid_over(PlanarSettings, settings, options, "solve")
    as_printed = st.as_printed
    enc = st.encoding or scenario.encoding
    prob = problem or make_problem(scenario, enc, **(st.encoding_params or {}))
    pop_default, iter_default = (PAPER_BUDGET if as_printed else DEFAULT_BUDGET)[enc]
    params = dict(st.optimizer_params or {})
    if not as_printed and "init" not in params and _takes_problem_init(algorithm):
        params["init"] = "problem"
    opt = get_optimizer(algorithm, pop_size=st.pop_size or pop_default, **params)
    t0 = time.perf_counter()
    res = minimize(prob, opt, max_iter=st.max_iter or iter_default, rng=rng)
    seconds = time.perf_counter() - t0
    pts = prob.path(res.x_array)
    X = getattr(opt, "X", None)
    # multi-swarm optimisers keep (swarms, NP, n_var): DI over all their individuals
    ok = isinstance(X, np.ndarray) and X.ndim >= 2 and X.shape[-1] == prob.n_var
    div = population_diversity(X.reshape(-1, prob.n_var)) if ok else float("nan")
    stages: tuple[PlanarStage, ...] = ()
    exact_enc = enc
    if not as_printed:
        t1 = time.perf_counter()
        pts, stages = run_stages(scenario, pts, seconds, _roadmap(prob))
        seconds += time.perf_counter() - t1
        exact_enc = "segments"  # the final path is any-angle: the any-angle optimum
    m = measure(pts, scenario.world)
    # as printed: the encoding's own criterion (graze-tolerant for splines); default: strict
    success = bool(prob.success(res.x_array[None])[0]) if as_printed else m.collisions == 0
    optimum, method = float("nan"), ""
    if st.with_optimum:
        ex = exact_optimum(scenario, exact_enc)
        optimum, method = ex.length, ex.method
    return PlanarRun(
        scenario=scenario.name,
        algorithm=algorithm,
        encoding=enc,
        points=tuple((float(x), float(y)) for x, y in pts),
        length=m.length,
        smoothness=m.smoothness,
        min_clearance=m.min_clearance,
        success=success,
        collisions=m.collisions,
        fitness=res.f,
        optimum=optimum,
        seconds=seconds,
        n_eval=res.n_eval,
        seed=seed_of(rng),
        history=res.history,
        diversity=div,
        pipeline="as-printed" if as_printed else "default",
        stages=stages,
        optimum_method=method,
    )


def _takes_problem_init(algorithm: str) -> bool:
    """Whether the optimiser accepts ``init="problem"`` (the roadmap seeding)."""
    try:
        get_optimizer(algorithm, init="problem")
    except (TypeError, ValueError):
        return False
    return True


def _roadmap(prob: PathProblem) -> np.ndarray | None:
    """The problem's roadmap path (cached on it when the seeding built it), or ``None``."""
    from weldplan.errors import PlanningError

    try:
        return prob.roadmap_path()
    except PlanningError:
        return None
