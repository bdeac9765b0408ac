"""The multi-goal tour planner: order the stops, join the legs, smooth, check.

Two pipelines (:func:`plan_tour`; ``weldplan planar tour``):

``default``
    The stops are ordered over **exact any-angle** leg lengths (Polyanya between every pair of
    stops, :mod:`weldplan.planar.tour_anyangle`), the optimiser's best order is polished by the
    sequencer's 2-opt + Or-opt search, the legs are Polyanya's shortest paths, and the tour is
    smoothed by the eq. 14 B-spline with its collision fallback. Named deviations from paper
    002: the any-angle costs and legs (002 uses Dijkstra along the triangle mesh, whose zig-zag
    makes its distances 0-7 % longer than the true ones, so its best order is optimal over the
    wrong costs) and the polish (see :mod:`weldplan.planar.multigoal`).
``as-printed`` (``as_printed=True``, ``--as-printed``)
    Paper 002 exactly: mesh-edge Dijkstra costs, the optimiser's order, no polish, the B-spline
    over the mesh-edge legs (no funnel).

Every answer carries the exact optimum beside it: Held-Karp (open/closed as the planner: closed
through the start) over the any-angle distance matrix, the shortest closed tour any planner can
drive through the stops on this map (with circles as the visibility graph's circumscribed
polygons); :attr:`TourResult.exact_gap` is the returned path's gap to it. ``stages`` keeps the
optimiser's own order cost beside what each added stage changed.
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import PlanningError
from weldplan.geometry.pathmetrics import path_length
from weldplan.optim.core import minimize
from weldplan.optim.discrete.sequence import SequenceSettings, solve_sequence
from weldplan.optim.registry import get_optimizer
from weldplan.planar.tour_anyangle import AnyAngleTourGraph, build_anyangle_graph
from weldplan.planar.tour_order import (
    EXACT_STOPS,
    RandomKeyTourProblem,
    TourGraph,
    build_tour_graph,
    polish_order,
    tour_lengths,
)
from weldplan.planar.tour_scenarios import TourScenario
from weldplan.planar.tour_settings import METRICS, TourSettings, split_options
from weldplan.planar.tour_smooth import segments_clear, smooth_tour
from weldplan.random import RNGLike, as_generator, seed_of

log = logging.getLogger(__name__)

__all__ = ["METRICS", "TourResult", "TourSettings", "ground_truth", "plan_tour"]


@dataclass(frozen=True)
class TourResult:
    """A planned multi-goal traversal.

    Attributes
    ----------
    scenario, algorithm
        What was solved, by what (``"exact"``/``"nn+polish"`` for the ground-truth sequencer).
    order
        Goal numbers (1..t) in visiting order; the tour starts and ends at the start (0).
    length
        Closed tour length over the distances that ordered the stops (``metric``): exact
        any-angle legs (Polyanya, the default) or mesh-edge shortest paths (paper 002).
    optimum
        The ground-truth (sequencer) tour length on the same distances.
    smooth_length
        Length of the returned (smoothed or fallback) path.
    smoothed
        Whether the B-spline was collision-free (else the polyline is returned).
    collision_free
        The final independent check of the returned path (exact: :attr:`TourScenario.exact_world`).
    points
        ``((q, 2))``: the returned path.
    seconds
        Ordering time (optimiser plus final polish); ``build_seconds`` the mesh + Dijkstra
        time, ``smooth_seconds`` the smoothing time.
    max_edge, mesh_nodes
        The mesh used.
    seed, n_eval, params
        Reproduction details.
    optimizer_length
        Closed length of the optimiser's own order, before the final polish (``None`` for the
        sequencer); with ``polished=False`` it equals ``length``.
    polyline_length
        Length of the polyline that was smoothed: the mesh-edge legs, or the taut ones
        (``taut=True``, the default), never longer than ``length``.
    polished
        Whether the final polish ran (a named deviation, see the module docstring).
    polish_seconds
        Time of the final polish (included in ``seconds``); ``cpu_seconds`` the process CPU
        time of the ordering (optimiser and polish), which a busy machine inflates less than
        the wall time; ``optimizer_cpu_seconds`` that of the optimiser alone.
        ``smooth_seconds`` covers the string pulling, the B-spline and the collision checks.
    metric
        ``"any-angle"`` (stops ordered over Polyanya's exact leg lengths, legs = Polyanya's
        paths) or ``"mesh"`` (paper 002: Dijkstra along mesh edges).
    pipeline
        ``"default"`` (any-angle costs, polish, B-spline), ``"as-printed"`` (paper 002: mesh
        costs, the optimiser's order, mesh-edge legs, B-spline) or ``"custom"``.
    exact_optimum, exact_order
        The exact optimal closed tour through the stops: Held-Karp over the any-angle distance
        matrix (the sequencer's nearest neighbour + polish above :data:`EXACT_STOPS` stops).
    legs_collision_free
        The independent exact check of the joined legs before smoothing.
    stages
        ``(name, length, seconds, note)`` per stage: the optimiser's own order, then what each
        added stage made of it (polish, funnel, B-spline).
    """

    scenario: str
    algorithm: str
    order: tuple[int, ...]
    length: float
    optimum: float
    smooth_length: float
    smoothed: bool
    collision_free: bool
    points: tuple[tuple[float, float], ...]
    seconds: float
    build_seconds: float
    smooth_seconds: float
    max_edge: float
    mesh_nodes: int
    seed: int | None = None
    n_eval: int = 0
    params: dict[str, Any] = field(default_factory=dict)
    optimizer_length: float | None = None
    polyline_length: float | None = None
    polished: bool = False
    polish_seconds: float = 0.0
    cpu_seconds: float = 0.0
    optimizer_cpu_seconds: float = 0.0
    metric: str = "mesh"
    pipeline: str = "custom"
    exact_optimum: float | None = None
    exact_order: tuple[int, ...] = ()
    legs_collision_free: bool | None = None
    stages: tuple[tuple[str, float, float, str], ...] = ()

    @property
    def gap(self) -> float:
        """Relative gap of the order to the ground-truth order (0.01 = 1 %)."""
        return self.length / self.optimum - 1.0

    @property
    def optimizer_gap(self) -> float:
        """Relative gap of the optimiser's own order (before the polish) to the ground truth."""
        L = self.length if self.optimizer_length is None else self.optimizer_length
        return L / self.optimum - 1.0

    @property
    def exact_gap(self) -> float:
        """Relative gap of the returned path to the exact optimal tour (``nan`` when unknown)."""
        if not self.exact_optimum:
            return float("nan")
        return self.smooth_length / self.exact_optimum - 1.0

    @property
    def points_array(self) -> NDArray[np.float64]:
        return np.asarray(self.points, dtype=np.float64)

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> TourResult:
        d = json.loads(text)
        d["order"] = tuple(d["order"])
        d["points"] = tuple(tuple(p) for p in d["points"])
        d["exact_order"] = tuple(d.get("exact_order", ()))
        d["stages"] = tuple(tuple(s) for s in d.get("stages", ()))
        return cls(**d)


def ground_truth(
    graph: TourGraph | AnyAngleTourGraph, rng: RNGLike = 0
) -> tuple[tuple[int, ...], float, str]:
    """The sequencer's closed tour from the start over ``graph.dist``: ``(goal order, length,
    method)``; Held-Karp (exact) up to :data:`EXACT_STOPS` stops."""
    n = graph.dist.shape[0]
    method = "exact" if n <= EXACT_STOPS else "nn"
    seq = solve_sequence(graph.dist, SequenceSettings(method, closed=True, first=0), rng=rng)
    order = list(seq.order)
    k = order.index(0)
    order = order[k:] + order[:k]
    return tuple(order[1:]), float(seq.cost), seq.method


def _ordering(
    g: TourGraph | AnyAngleTourGraph,
    algorithm: str,
    gen: np.random.Generator,
    *,
    name: str,
    polish: bool,
    polish_kicks: int | None,
    two_opt: bool,
    budget: dict[str, Any],
    params: dict[str, Any],
) -> dict[str, Any]:
    """Run the optimiser on the random keys over ``g.dist`` and the optional polish."""
    cpu0 = time.process_time()
    problem = RandomKeyTourProblem(g.dist, two_opt=two_opt, name=name)
    opt = get_optimizer(algorithm, pop_size=budget["pop_size"], **params)
    res = minimize(problem, opt, **{k: v for k, v in budget.items() if k != "pop_size"}, rng=gen)
    best = problem.orders(res.x_array)[0]
    opt_length = float(tour_lengths(g.dist, best[None])[0])
    cpu_opt = time.process_time() - cpu0
    length, polish_s = opt_length, 0.0
    if polish:
        tp = time.perf_counter()
        best, length = polish_order(g.dist, best, gen, kicks=polish_kicks)
        polish_s = time.perf_counter() - tp
    return {
        "order": tuple(int(v) for v in best),
        "length": length,
        "opt_length": opt_length,
        "opt_seconds": res.seconds,
        "polish_seconds": polish_s,
        "cpu": time.process_time() - cpu0,
        "cpu_opt": cpu_opt,
        "n_eval": res.n_eval,
        "params": {
            **res.params,
            **budget,
            "two_opt": two_opt,
            "polish": polish,
            "polish_kicks": polish_kicks,
        },  # fmt: skip
    }


def _graphs(
    task: TourScenario,
    metric: str,
    graph: TourGraph | None,
    anyangle: AnyAngleTourGraph | None,
    exact: tuple[tuple[int, ...], float] | None,
) -> tuple[TourGraph | AnyAngleTourGraph, tuple[tuple[int, ...], float]]:
    """The graph whose distances order the stops (any-angle or mesh-edge, built unless given)
    and the exact any-angle optimal tour ``(order, length)`` (computed unless given).

    Raises
    ------
    PlanningError
        When some stop cannot be reached.
    """
    if exact is None or metric == "any-angle":
        anyangle = build_anyangle_graph(task) if anyangle is None else anyangle
    if exact is None:
        ex_order, ex_len, _ = ground_truth(anyangle)
        exact = (ex_order, ex_len)
    if metric == "any-angle":
        g: TourGraph | AnyAngleTourGraph = anyangle
    else:
        g = build_tour_graph(task) if graph is None else graph
    if not np.all(np.isfinite(g.dist)):
        raise PlanningError(f"{task.name}: some goals cannot be reached on the mesh")
    return g, exact


def _join_and_smooth(
    task: TourScenario,
    g: TourGraph | AnyAngleTourGraph,
    order: Any,
    metric: str,
    taut: bool,
    smooth: bool,
    stages: list[tuple[str, float, float, str]],
) -> tuple[NDArray[np.float64], bool, NDArray[np.float64], bool]:
    """Join the legs of ``order`` into the closed polyline (pulled taut with the mesh metric
    and ``taut``) and smooth it (eq. 14 B-spline with the collision fallback) when ``smooth``;
    appends the ``funnel`` and ``spline`` stages. Returns ``(polyline (p, 2), its legs are
    free by the exact check, curve (q, 2), smoothed)``."""
    t1 = time.perf_counter()
    poly, at = g.polyline(order, taut=taut)
    legs_free = bool(segments_clear(task.exact_world, poly[:-1], poly[1:]).all())
    if metric == "mesh" and taut:
        stages.append(("funnel", float(path_length(poly)), time.perf_counter() - t1,
                       "legs pulled taut in their triangle corridors"))  # fmt: skip
    t2 = time.perf_counter()
    if smooth:
        curve, smoothed = smooth_tour(poly, at, task.world)
    else:
        curve, smoothed = poly, False
    if smooth:
        note = "B-spline (eq. 14)" if smoothed else "spline collided: polyline kept"
        stages.append(("spline", float(path_length(curve)), time.perf_counter() - t2, note))
    return poly, legs_free, curve, smoothed


def plan_tour(
    task: TourScenario,
    algorithm: str = "isma",
    settings: TourSettings | None = None,
    *,
    graph: TourGraph | None = None,
    anyangle: AnyAngleTourGraph | None = None,
    optimum: float | None = None,
    exact: tuple[tuple[int, ...], float] | None = None,
    rng: RNGLike = None,
    **params: Any,
) -> TourResult:
    """Plan a closed multi-goal tour on ``task``'s map (module docstring).

    Parameters
    ----------
    algorithm
        A registered optimiser name (``isma``, ``sma``, ``woa``, ``lso``, ...) for the random-key
        order, or ``"exact"`` for the ground-truth sequencer on the same distances.
    settings
        The leg metric, the pipeline's stages and the optimiser's budget
        (:class:`~weldplan.planar.tour_settings.TourSettings`); ``None``: the default pipeline
        with paper 002's budget (500 x 500).
    graph, anyangle
        A prebuilt mesh-edge :class:`TourGraph` and any-angle
        :class:`~weldplan.planar.tour_anyangle.AnyAngleTourGraph` (to share them between runs);
        built when needed and not given.
    optimum
        The ground-truth length over the ordering metric's distances, when already known.
    exact
        ``(order, length)`` of the exact any-angle optimal tour, when already known.
    rng
        Seed or Generator.
    params
        A keyword naming a :class:`~weldplan.planar.tour_settings.TourSettings` field
        (``metric="mesh"``, ``pop_size=60``, ``polish=False``...) is laid over ``settings``;
        the others are the optimiser's parameters.

    Raises
    ------
    ConfigError
        For contradictory settings (``as_printed`` with ``metric='any-angle'``, ``taut=False``
        with any-angle legs, an unknown metric), naming the field.
    PlanningError
        When some stop cannot be reached.
    """
    st, params = split_options(settings, params)
    metric, polish, taut = st.resolved()
    gen = as_generator(rng)
    seed = seed_of(rng)
    g, exact = _graphs(task, metric, graph, anyangle, exact)
    gt = None
    if optimum is None or algorithm == "exact":
        t0 = time.perf_counter()
        gt_order, gt_len, gt_method = ground_truth(g, rng=gen)
        gt = (gt_order, gt_len, gt_method, time.perf_counter() - t0)
        optimum = gt_len
    stages: list[tuple[str, float, float, str]] = []
    run = _order_stage(task, g, algorithm, gen, metric, gt, stages, polish=polish,
                       polish_kicks=st.polish_kicks, two_opt=st.two_opt, budget=st.budget,
                       params=params)  # fmt: skip
    t1 = time.perf_counter()
    joined = _join_and_smooth(task, g, run["order"], metric, taut, st.smooth, stages)
    smooth_seconds = time.perf_counter() - t1
    return _tour_result(task, g, run, joined, stages, st=st, optimum=optimum, exact=exact,
                        seed=seed, smooth_seconds=smooth_seconds)  # fmt: skip


def _order_stage(
    task: TourScenario,
    g: TourGraph | AnyAngleTourGraph,
    algorithm: str,
    gen: np.random.Generator,
    metric: str,
    gt: tuple[tuple[int, ...], float, str, float] | None,
    stages: list[tuple[str, float, float, str]],
    **ordering: Any,
) -> dict[str, Any]:
    """The stops' order: the ground truth ``gt`` ``(order, length, method, seconds)`` for
    ``"exact"``, else the optimiser (and the polish) by :func:`_ordering` (``**ordering``: its
    keywords). Appends the ``order`` (and ``polish``) stages; returns ``order``, ``length``,
    ``name``, ``seconds``, ``used`` (the parameters), ``o`` (:func:`_ordering`'s record) and
    ``polished`` (whether the final polish ran)."""
    if algorithm == "exact":
        assert gt is not None
        order, length, gt_method, seconds = gt
        o: dict[str, Any] = {"opt_length": None, "polish_seconds": 0.0, "cpu": 0.0,
                             "cpu_opt": 0.0, "n_eval": 0}  # fmt: skip
        stages.append(("order", length, seconds, f"sequencer ({gt_method}) over {metric} costs"))
        return {"order": order, "length": length, "name": gt_method, "seconds": seconds,
                "used": {}, "o": o, "polished": False}  # fmt: skip
    o = _ordering(g, algorithm, gen, name=task.name, **ordering)
    stages.append(("order", o["opt_length"], o["opt_seconds"],
                   f"{algorithm}'s own order over {metric} costs"))  # fmt: skip
    if ordering["polish"]:
        stages.append(("polish", o["length"], o["polish_seconds"], "2-opt/Or-opt ILS"))
    return {"order": o["order"], "length": o["length"], "name": algorithm,
            "seconds": o["opt_seconds"] + o["polish_seconds"], "used": o["params"],
            "o": o, "polished": bool(ordering["polish"])}  # fmt: skip


def _tour_result(
    task: TourScenario,
    g: TourGraph | AnyAngleTourGraph,
    run: dict[str, Any],
    joined: tuple[NDArray[np.float64], bool, NDArray[np.float64], bool],
    stages: list[tuple[str, float, float, str]],
    *,
    st: TourSettings,
    optimum: float,
    exact: tuple[tuple[int, ...], float],
    seed: int | None,
    smooth_seconds: float,
) -> TourResult:
    """The final independent check of the returned curve and the :class:`TourResult` of
    :func:`plan_tour` (``run``: :func:`_order_stage`; ``joined``: :func:`_join_and_smooth`;
    ``st``: the run's settings)."""
    metric, pipeline = st.resolved()[0], st.pipeline
    poly, legs_free, curve, smoothed = joined
    order, length, name, seconds, o = (run[k] for k in ("order", "length", "name", "seconds", "o"))
    # the independent final check is exact, also where the loop sampled (grid maps)
    free = bool(segments_clear(task.exact_world, curve[:-1], curve[1:]).all())
    log.info("%s %s (%s): tour %.6g (optimum %.6g, exact any-angle %.6g), smoothed %.6g in %.3f s",
             task.name, name, pipeline, length, optimum, exact[1], float(path_length(curve)),
             seconds)  # fmt: skip
    mesh_nodes = g.n_nodes if isinstance(g, AnyAngleTourGraph) else g.mesh.n_nodes
    max_edge = g.max_edge if isinstance(g, AnyAngleTourGraph) else g.mesh.max_edge
    return TourResult(
        scenario=task.name,
        algorithm=name,
        order=tuple(order),
        length=float(length),
        optimum=float(optimum),
        smooth_length=float(path_length(curve)),
        smoothed=bool(smoothed),
        collision_free=free,
        points=tuple((float(x), float(y)) for x, y in curve),
        seconds=float(seconds),
        build_seconds=float(g.build_seconds),
        smooth_seconds=float(smooth_seconds),
        max_edge=float(max_edge),
        mesh_nodes=int(mesh_nodes),
        seed=seed,
        n_eval=int(o["n_eval"]),
        params=run["used"],
        optimizer_length=o["opt_length"],
        polyline_length=float(path_length(poly)),
        polished=bool(run["polished"]),
        polish_seconds=float(o["polish_seconds"]),
        cpu_seconds=float(o["cpu"]),
        optimizer_cpu_seconds=float(o["cpu_opt"]),
        metric=metric,
        pipeline=pipeline,
        exact_optimum=float(exact[1]),
        exact_order=tuple(int(v) for v in exact[0]),
        legs_collision_free=legs_free,
        stages=tuple((str(a), float(b), float(c), str(d)) for a, b, c, d in stages),
    )
