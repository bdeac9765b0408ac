"""The main job: a cell in, an ordered collision-free route out (``weldplan plan``).

Data flow (../shared/DESIGN.md)::

    Cell (part, joints, grid, collision model, virtual joints)
      -> straight check of every pair of virtual joints (one vectorised FCL call)
      -> local paths for blocked pairs (SO-ACO or exact grid search), through an Executor
      -> cost matrix -> sequencer (Held-Karp | TSP-PSO + polish) -> Route

Which pairs get planned: lazily
-------------------------------
A leg from joint ``i`` to joint ``j`` goes weld spot -> virtual joint -> ... -> virtual joint ->
weld spot. Its cost is known at once when the straight segment between the two virtual joints is
free at the clearance (one capsule check). For a blocked pair the cost is first *estimated* by that
same straight polyline, which is a lower bound of any path through the two virtual joints. The
sequencer orders the joints with these costs; the blocked legs the order actually uses are then
planned (in parallel through the executor), their true lengths replace the estimates, and the
sequencer runs again, until the order uses only known legs (each round plans at least one new
pair, so this ends). With an exact sequencer the result is the optimum over the planner's path
lengths, having planned only the blocked pairs that could matter; ``PlanConfig(pairs="all")`` plans
every blocked pair up front instead (the dense matrix the paper builds). When the sequencer is a
heuristic and the cell small enough for Held-Karp (up to 16 joints), the discovery rounds run
Held-Karp, then the configured sequencer orders the joints once more (and, in the rare case that
its order uses a leg still unknown, the rounds go on with it).

Candidate pairs (station scale)
-------------------------------
At hundreds of joints even the straight checks of all ``n (n - 1) / 2`` pairs are more than the
sequencer needs. ``PlanConfig(candidates=k)`` checks up front only the candidate pairs: each
joint with its ``k`` nearest joints by straight-line distance between the weld spots. The straight
segment is checked first; the blocked candidates are then searched in one batch through the
executor (the work that parallelises). Every other pair keeps its straight-polyline estimate (a
lower bound, as above) until an order uses it; then it is checked on demand, straight first and
searched only if blocked, and the sequencer runs again. With an exact sequencer the route is the
same as with every pair planned. Above :data:`LOWER_BOUND_EXACT_MAX` joints a heuristic sequencer
orders over the known legs first (``PlanConfig.known_first``): an unknown leg costs its estimate
plus a penalty larger than any route over known legs, so it is used, and then planned, only
where the known legs leave no way through (optimistic estimates kept the 1000-joint rounds from
ever settling). ``Route.stats`` counts the pairs checked, straight, searched
(``pairs_checked``, ``pairs_straight``, ``pairs_planned``) and the candidates.

Warm rounds (station scale)
---------------------------
Each round of the lazy mode runs the sequencer again. Above :data:`LOWER_BOUND_EXACT_MAX` joints
with a heuristic sequencer, the second and later rounds polish the previous round's order (only
the legs planned in between changed cost; ``PlanConfig.warm_rounds``, ``warm_kicks``) instead of
solving from scratch: a fresh polish at 1000 joints makes 10,000 kicks (about 40 s), and the
1000-joint car2 set needed tens of rounds.

With the default sequencer above 13 joints (``"nn"``: nearest neighbour and the seeded polish,
reproducible) and with fast-tsp (no warm start, not reproducible: legs not yet known are
*avoided* rather than penalised), the rounds go on past the first route:
:func:`weldplan.weld.converge.close_gap`
plans the legs that optimistic orders (over planned lengths and lower-bound estimates) use
until the route is within ``PlanConfig.gap_target`` of one; ``Route.stats["gap_planned"]`` is
then the route's gap to the proved bound over the same costs (``bound_planned``).

Randomness: one generator, normalised once from ``rng``; each pair gets its own seed drawn from it
up front in a fixed order, so a route does not depend on the executor or the order in which
workers finish.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping
from concurrent.futures import Executor
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError, UnreachableJointsError
from weldplan.random import RNGLike, as_generator, seed_of
from weldplan.weld.pairs import PairPlanning
from weldplan.weld.pairtasks import (  # noqa: F401 - public here as before
    _plan_pair_task,
    _plan_pairs_task,
    candidate_pairs,
)
from weldplan.weld.route import Leg, Route
from weldplan.weld.skip import reachable_subset, with_skipped
from weldplan.weld.validate import PLANNERS, SEQUENCERS  # noqa: F401 - public here as before

log = logging.getLogger(__name__)

#: progress callback: ``progress(stage, done, total)``; stages "straight", "local", "sequence"
Progress = Callable[[str, int, int], None]

#: the exact straight-line lower bound (Held-Karp) is used up to this many joints, else the
#: 1-tree bound
LOWER_BOUND_EXACT_MAX = 16
#: CPU-time cap of the 1-tree bound's subgradient ascent (s of the calling thread): 200 joints
#: finish in ~3 s
LOWER_BOUND_SECONDS = 10.0

#: SO-ACO settings of the demo target (N = M = 10; the paper's Table 3 also runs 50/50)
DEFAULT_ACO: dict[str, Any] = {"n_iterations": 10, "n_ants": 10}


@dataclass(frozen=True)
class PlanConfig:
    """Every setting of a planning run (recorded in the Route).

    Attributes
    ----------
    clearance, pitch, margin
        mm: torch-tip radius, voxel pitch and region-of-interest margin of the cell. They are used
        when the cell is built (``weldplan plan``, :func:`weldplan.weld.cell.load_cell`);
        :func:`plan_route` plans in the cell it is given and records the cell's own values.
    planner
        Local planner for blocked pairs: ``"exact"`` (the default: 26-connected A* + the
        paper's secondary optimisation, then :attr:`refine`; on the blocked pairs of
        ``weldplan bench local --peers`` it is both shorter and about 100x cheaper than SO-ACO),
        ``"so-aco"`` (the paper's Wang et al. 2017 planner, as printed with ``refine=False``),
        ``"aco"`` or ``"ompl"`` (OMPL's BIT*, needs the ompl extra).
    sequencer
        ``"auto"`` (Held-Karp up to 13 joints, else ``"nn"``), ``"fast-tsp"`` (not
        reproducible: :mod:`weldplan.optim.discrete.sequence`), ``"pso"`` (the paper's TSP-PSO
        + polish), ``"exact"``, ``"nn"`` (nearest neighbour + the seeded polish).
    pairs
        ``"lazy"`` (plan the blocked pairs the order uses, module docstring) or ``"all"``.
    aco
        Parameters passed to the local planner (``params=`` of ``plan_pair``); the default is
        :data:`DEFAULT_ACO` (N = M = 10), the rest are the paper's (alpha 1, beta 11, rho 0.9,
        Q 5, tau0 0.5, 5 mm moves).
    pso
        TSP-PSO parameters (``PSOParams`` fields); empty = the paper's (100 iterations, 50
        particles, c1 = c2 = 1, w = 0.4).
    polish
        2-opt / Or-opt polish after the swarm.
    local_time_budget
        Seconds per local-path search (None: no limit).
    sequence_time_budget
        Seconds for each run of the sequencer's polish (None: its own stopping rule).
    max_rounds
        Bound on plan-then-sequence rounds of the lazy mode; after it every blocked pair is
        planned and the sequencer runs once more (without candidates; with candidates the rounds
        go on, each planning at least one new pair, so they end).
    candidates
        ``k``: check and plan up front only each joint's ``k`` nearest neighbours, the other pairs
        on demand (module docstring); None: every pair is checked straight up front. Only with
        ``pairs="lazy"``.
    candidate_radius
        mm: with ``candidates``, a neighbour farther than this is left to on demand (on car2's
        1000-joint set some of the 6 nearest are 476 mm away behind a panel, whose searches
        cost minutes each); None: no limit.
    warm_rounds
        Above :data:`LOWER_BOUND_EXACT_MAX` joints, the second and later lazy rounds start the
        heuristic sequencer's polish from the previous round's order (only the legs planned in
        between changed cost) instead of solving again from scratch; see ``warm_kicks``. The
        polish of a fresh solve makes 10 kicks per joint (40 s a round at 1000 joints, and
        the 1000-joint set takes tens of rounds). False: every round solves from scratch.
    warm_kicks
        Double-bridge kicks of the warm polish that accepts an order; None: one per joint. The
        rounds in between run the descent only (2-opt + Or-opt, no kicks), as long as each
        finds legs still unknown.
    demand_neighbours
        Above :data:`LOWER_BOUND_EXACT_MAX` joints, when an order uses unknown legs, the unknown
        pairs from each of their ends to its ``demand_neighbours`` nearest joints (by current
        cost) are planned in the same round: they are the moves the polish tries next, and
        planning them together saves rounds (each a sequencer run). 0: only the legs used.
    known_first
        With ``candidates``, above :data:`LOWER_BOUND_EXACT_MAX` joints and a heuristic
        sequencer: a leg not yet known costs its estimate plus a penalty larger than any route
        over known legs, so the sequencer orders over the known legs (the candidates) and
        uses an unknown one only where it must (it is then planned and the round repeats), the
        way candidate-set TSP heuristics work. Without it, every unknown leg is costed by its
        optimistic estimate and at 1000 joints the rounds never settle (279 rounds and 5,030
        pairs planned in 13 minutes on car2's set). Exact sequencers always use estimates
        (their route is then the all-pairs optimum).
    skip_unreachable
        Plan the largest group of mutually reachable joints and list the others, with the
        reason, in ``route.stats["skipped"]`` (:mod:`weldplan.weld.skip`), instead of raising
        :class:`~weldplan.errors.UnreachableJointsError`.
    memory_limit
        GB the run may use; the pair work is estimated up front (:mod:`weldplan.weld.sizing`)
        and refused with a :class:`~weldplan.errors.ConfigError` when it would not fit. None:
        :func:`~weldplan.weld.sizing.default_memory_limit` (a fraction of the available memory).

    Every field is checked when the config is made (:mod:`weldplan.weld.validate`): a wrong type,
    NaN or out-of-range value raises :class:`~weldplan.errors.ConfigError`, a ``ValueError``.
    gap_target
        With the nn or fast-tsp sequencer above :data:`LOWER_BOUND_EXACT_MAX` joints, lazy mode:
        after the known-first rounds, plan the legs that optimistic orders (over planned
        lengths and lower-bound estimates) use until the route is within this relative gap of
        such an order (:func:`weldplan.weld.converge.close_gap`); the proved bound and gap are
        reported in ``Route.stats`` (``bound_planned``, ``gap_planned``). None: off.
    gap_rounds
        Bound on those rounds.
    refine
        Run the continuous refinement after the grid planner (:mod:`weldplan.weld.refine`:
        shortcuts anywhere on the path, vertices slid to the clearance, re-checked by FCL): on
        by default, the best pipeline; False (``weldplan plan --no-refine``) plans the paper's
        SO-ACO as printed. It is passed to the planner as ``aco["refine"]`` (an explicit
        ``aco["refine"]`` wins).
    smooth
        After the route is built, give each leg a smooth path (:mod:`weldplan.weld.smoothing`:
        a C2 curve between its virtual joints, exported as dense waypoints whose chords are
        checked by FCL at the clearance); a leg whose curve fails keeps its polyline and
        ``Route.stats["smooth"]`` says why. Off by default (``weldplan plan --smooth``): the
        polyline stays the route the robot stages read.
    smooth_spacing
        mm, the largest spacing of the smooth waypoints along the curve (denser where a chord
        would cut a bend into the clearance).
    """

    clearance: float = 5.0
    pitch: float = 5.0
    margin: float = 150.0
    planner: str = "exact"
    sequencer: str = "auto"
    pairs: str = "lazy"
    aco: Mapping[str, Any] = field(default_factory=lambda: dict(DEFAULT_ACO))
    pso: Mapping[str, Any] = field(default_factory=dict)
    polish: bool = True
    local_time_budget: float | None = None
    sequence_time_budget: float | None = None
    max_rounds: int = 50
    candidates: int | None = None
    candidate_radius: float | None = None
    warm_rounds: bool = True
    warm_kicks: int | None = None
    demand_neighbours: int = 10
    known_first: bool = True
    skip_unreachable: bool = False
    memory_limit: float | None = None
    gap_target: float | None = 0.01
    gap_rounds: int = 30
    refine: bool = True
    smooth: bool = False
    smooth_spacing: float = 5.0

    def __post_init__(self) -> None:
        from weldplan.weld.validate import check_config

        check_config(self)  # ConfigError (a ValueError) naming the field; normalises in place

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> PlanConfig:
        names = cls.__dataclass_fields__
        return cls(**{k: v for k, v in d.items() if k in names})


def straight_lower_bound(xyz: NDArray[np.float64]) -> tuple[float, str]:
    """Open-path lower bound over straight-line distances between the weld spots ``(n, 3)``.

    Held-Karp's optimum up to :data:`LOWER_BOUND_EXACT_MAX` joints (``"held-karp"``), else
    Held and Karp's 1-tree bound with subgradient ascent (``"1-tree"``,
    :func:`weldplan.optim.discrete.bounds.one_tree_bound`, at most
    :data:`LOWER_BOUND_SECONDS`), which is never below the minimum spanning tree's weight
    (every open path is a spanning tree) and typically within 1-2 % of the optimum where the
    spanning tree is 10 % below it.
    """
    bound, method, _ = _straight_bound(xyz)
    return bound, method


def _straight_bound(xyz: NDArray[np.float64]) -> tuple[float, str, bool]:
    """:func:`straight_lower_bound` and whether its CPU-time cap stopped the 1-tree ascent."""
    n = len(xyz)
    if n < 2:
        return 0.0, "trivial", False
    D = np.linalg.norm(xyz[:, None, :] - xyz[None, :, :], axis=-1)
    if n <= LOWER_BOUND_EXACT_MAX:
        from weldplan.optim.discrete.sequence import solve_sequence

        return float(solve_sequence(D, method="exact").cost), "held-karp", False
    from scipy.sparse.csgraph import minimum_spanning_tree

    from weldplan.optim.discrete.bounds import one_tree

    mst = float(minimum_spanning_tree(D).sum())
    tree = one_tree(D, open_path=True, max_seconds=LOWER_BOUND_SECONDS)
    if tree.bound > mst:
        return tree.bound, "1-tree", tree.clock_stopped
    return mst, "mst", False


def plan_route(
    cell: Any,
    *,
    config: PlanConfig | None = None,
    rng: RNGLike = None,
    executor: Executor | None = None,
    progress: Progress | None = None,
    leg_cost: NDArray[np.float64] | None = None,
) -> Route:
    """Plan the ordered, collision-free route through every joint of ``cell``.

    Parameters
    ----------
    cell
        A :class:`~weldplan.weld.cell.Cell` (part, joints, grid, collision model, virtual joints).
    config
        Planner, sequencer and their parameters (:class:`PlanConfig`). With
        ``skip_unreachable=True``, joints that have no collision-free path to the largest group
        of joints are left out and listed in ``route.stats["skipped"]`` (``[{"id", "reason"}]``)
        instead of failing the whole run.
    rng
        Seed (an integer >= 0, as numpy takes), SeedSequence or Generator; the only source of
        randomness of the run.
    executor
        Where blocked pairs are planned: any ``concurrent.futures.Executor`` (a process pool, a
        Dask ``Client.get_executor()``); serial in this process when None. The cell reaches each
        worker once (:mod:`weldplan.weld.parallel`; :func:`~weldplan.weld.parallel.process_pool`
        installs it at worker start); pairs travel in batches.
    progress
        ``progress(stage, done, total)`` for the stages ``"straight"``, ``"local"``,
        ``"sequence"``.
    leg_cost
        ``(n, n)`` over the cell's joints: what the sequencer minimises instead of length
        (``weldplan plan --cost time``; :class:`~weldplan.weld.pairs.PairPlanning`). The route's
        length bounds stay in mm.

    Returns
    -------
    Route
        Not yet verified: call :func:`weldplan.weld.verify.verify_route` (``weldplan plan`` does).

    Raises
    ------
    ConfigError
        A bad argument (wrong type, out of range, NaN), before any work; a ``ValueError``. Also
        when the pair work of this many joints would not fit ``config.memory_limit``
        (:mod:`weldplan.weld.sizing`).
    PlanningError
        When no order of finite cost exists (e.g. a joint every local path to which failed);
        :class:`~weldplan.errors.UnreachableJointsError` names the groups of joints.
    """
    from weldplan.weld.sizing import check_pair_work
    from weldplan.weld.validate import check_plan_arguments

    config = PlanConfig() if config is None else config
    if not isinstance(config, PlanConfig):
        raise ConfigError(
            f"config must be a PlanConfig, got {type(config).__name__}", field="config"
        )
    check_plan_arguments(cell, rng, executor, progress)
    check_pair_work(len(cell.joints.ids), config.candidates, config.memory_limit)
    seed = seed_of(rng)
    report = progress or (lambda stage, done, total: None)
    if not config.skip_unreachable:
        return _plan(cell, config, as_generator(rng), seed, executor, report, leg_cost=leg_cost)
    subset = None
    skipped: list[dict[str, str]] = []
    while True:  # each pass leaves out at least one joint, so this ends
        try:
            # a seed starts each pass afresh: the route is the one of the kept joints alone
            gen = as_generator(rng)
            route = _plan(cell, config, gen, seed, executor, report, subset, leg_cost)
        except UnreachableJointsError as exc:
            subset, more = reachable_subset(cell, subset, exc, float(cell.clearance))
            log.warning("skipping %d unreachable joint(s): %s", len(more), exc)
            skipped += more
            continue
        return with_skipped(route, cell, skipped) if skipped else route


def _plan(
    cell: Any,
    config: PlanConfig,
    gen: np.random.Generator,
    seed: int | None,
    executor: Executor | None,
    report: Progress,
    subset: NDArray[np.intp] | None = None,
    leg_cost: NDArray[np.float64] | None = None,
) -> Route:
    """Straight checks, lazy rounds, then the route with its bounds and figures (over the
    joints ``subset`` of the cell, all when None)."""
    t_start = time.perf_counter()
    work = PairPlanning(
        cell, config, gen, executor, report, LOWER_BOUND_EXACT_MAX, subset, leg_cost
    )
    seconds = {"straight": work.straight_stage()}
    seq = work.run()
    seconds["local"] = work.t_local
    seconds["sequence"] = work.t_seq
    order = list(seq.order)
    legs = _legs(work, order)
    t0 = time.perf_counter()
    lb, lb_method, lb_clock = _straight_bound(work.P)
    bounds = _route_bounds(work, seq)
    bounds["clock_stops"] = _clock_stops(work, lb_clock, bounds.pop("bound_planned_clock"))
    seconds["lower_bound"] = time.perf_counter() - t0
    seconds["total"] = time.perf_counter() - t_start
    route = Route(
        order=tuple(work.ids[k] for k in order),
        legs=tuple(legs),
        joint_ids=work.ids,
        joint_xyz=work.P,
        directions=work.directions,
        virtual_xyz=work.V,
        lower_bound=lb,
        lower_bound_method=lb_method,
        settings=_settings(cell, config, work.clearance),
        seed=seed,
        stats=_stats(work, seq, legs, bounds, seconds),
        provenance=dict(getattr(cell, "provenance", None) or {}),
    )
    if config.smooth:
        from weldplan.weld.smoothing import smooth_route

        route = smooth_route(route, cell, spacing=config.smooth_spacing)
        seconds["smooth"] = route.stats["smooth"]["seconds"]
        seconds["total"] = time.perf_counter() - t_start
        route.stats["seconds"] = {k: round(v, 6) for k, v in seconds.items()}
    log.info(
        "route %.2f mm (lower bound %.2f mm), %d pairs planned, %.2f s",
        route.length,
        lb,
        len(work.paths),
        seconds["total"],
    )
    return route


def _legs(work: PairPlanning, order: list[int]) -> list[Leg]:
    """The legs of ``order``: a planned pair's local path, else the straight polyline
    spot -> virtual joint -> virtual joint -> spot."""
    P, V, ids = work.P, work.V, work.ids
    legs = []
    for a, b in zip(order[:-1], order[1:], strict=True):
        p = int(work.pair_index[a, b])
        if p in work.paths:
            lp = work.paths[p]
            pts = np.asarray(lp.points, dtype=float)
            if a > b:
                pts = pts[::-1]
            leg = Leg(ids[a], ids[b], pts, str(getattr(lp, "method", work.config.planner)))
        else:
            pts = np.array([P[a], V[a], V[b], P[b]])
            # drop repeats: a joint that is its own virtual joint, two joints sharing one
            keep = np.r_[True, np.any(pts[1:] != pts[:-1], axis=1)]
            leg = Leg(ids[a], ids[b], pts[keep] if keep.sum() >= 2 else pts[[0, -1]], "straight")
        legs.append(leg)
    return legs


def _route_bounds(work: PairPlanning, seq: Any) -> dict[str, Any]:
    """The two bounds tighter than the straight-line one (``Route.stats``)."""
    from weldplan.optim.discrete.sequence import solve_sequence

    n, iu, ju, C, est = work.n, work.iu, work.ju, work.C, work.est
    # A tighter bound on the whole route: every leg costs at least its straight polyline
    # spot -> virtual -> virtual -> spot (the estimates), so the optimum over them bounds
    # every route through these virtual joints, approaches included.
    bound_appr = float("nan")
    # The measure "between virtual joints" (the route without its approaches) is bounded by the
    # straight-line optimum over the virtual joints, not over the weld spots: a path through the
    # virtual joints can be shorter than the spots' bound (the refined demo route is).
    bound_virtual = float("nan")
    if 1 < n <= LOWER_BOUND_EXACT_MAX:
        E = np.zeros((n, n))
        E[iu, ju] = E[ju, iu] = est
        bound_appr = float(solve_sequence(E, method="exact").cost)
        bound_virtual = straight_lower_bound(work.V)[0]
    # The tightest bound we can state: every leg costs at least what is known of it (a planned
    # leg its local path, any other its straight polyline), so the optimum over those costs
    # bounds every route built from this planner's local paths, the all-pairs route included.
    Cb = C.copy()
    Cb[iu, ju] = Cb[ju, iu] = np.where(np.isfinite(C[iu, ju]), C[iu, ju], est)
    clock = False
    if n < 2:
        bound_planned, bound_planned_method = 0.0, "trivial"
    elif n <= LOWER_BOUND_EXACT_MAX:
        bound_planned = float(solve_sequence(Cb, method="exact").cost)
        bound_planned_method = "held-karp"
    else:
        from weldplan.optim.discrete.bounds import one_tree

        tree = one_tree(Cb, open_path=True, upper=float(seq.cost), max_seconds=LOWER_BOUND_SECONDS)
        bound_planned, clock = tree.bound, tree.clock_stopped
        bound_planned_method = "1-tree"
    return {
        "bound_with_approaches": bound_appr,
        "bound_virtual": bound_virtual,
        "bound_planned": bound_planned,
        "bound_planned_method": bound_planned_method,
        "bound_planned_clock": clock,
    }


def _clock_stops(work: PairPlanning, lower_bound: bool, bound_planned: bool) -> dict[str, Any]:
    """Where a CPU-time safety net of the route stage stopped work before its work bounds
    (``Route.stats["clock_stops"]``): the pairs whose refinement spent its cap
    (:attr:`~weldplan.weld.localpath.LocalParams.refine_budget`) and the 1-tree bounds cut at
    :data:`LOWER_BOUND_SECONDS`. All zero / False: the route and its figures do not depend on
    the machine's speed or load."""
    pairs = sorted(
        f"{work.ids[work.iu[p]]}-{work.ids[work.ju[p]]}"
        for p, lp in work.paths.items()
        if getattr(lp, "refine_clock_stops", 0)
    )
    return {"refine_pairs": pairs, "lower_bound": lower_bound, "bound_planned": bound_planned}


def _settings(cell: Any, config: PlanConfig, clearance: float) -> dict[str, Any]:
    """The config as recorded in the route, with the cell's own clearance, pitch and margin."""
    settings = config.to_dict()
    settings.update(
        clearance=clearance,
        pitch=float(getattr(cell, "pitch", config.pitch)),
        margin=float(getattr(cell, "margin", config.margin)),
    )
    depth = float(getattr(cell, "spot_depth", 0.0) or 0.0)
    if depth > 0.0:  # recorded only when set, so a route of spots on the surface reads as before
        settings["spot_depth"] = depth
    return settings


def _stats(
    work: PairPlanning,
    seq: Any,
    legs: list[Leg],
    bounds: dict[str, Any],
    seconds: dict[str, float],
) -> dict[str, Any]:
    """The figures of the run (``Route.stats``)."""
    ids, iu, ju, paths = work.ids, work.iu, work.ju, work.paths
    local_stats = {
        f"{ids[iu[p]]}-{ids[ju[p]]}": {
            "length": float(lp.length),
            "method": str(getattr(lp, "method", work.config.planner)),
            "history": [float(h) for h in getattr(lp, "history", ())],
            "seconds": float(getattr(lp, "seconds", 0.0)),
            "search_voxels": int(getattr(lp, "search_voxels", 0)),
        }
        for p, lp in sorted(paths.items())
    }
    return {
        "pairs": work.n_pairs,
        "pairs_checked": int(work.checked.sum()),
        "pairs_candidates": int(len(work.upfront)),
        "pairs_straight": int(work.free.sum()),
        "pairs_blocked": int((work.checked & ~work.free).sum()),
        "pairs_planned": len(paths),
        "pairs_failed": work.n_failed,
        "pairs_over_search_cap": sum(
            "max_search_voxels" in str(getattr(lp, "reason", "")) for lp in paths.values()
        ),
        "search_voxels_max": max(
            (int(getattr(lp, "search_voxels", 0)) for lp in paths.values()), default=0
        ),
        "rounds": work.rounds,
        "legs_planned": sum(leg.method != "straight" for leg in legs),
        **bounds,
        "gap_planned": (
            float(seq.cost / bounds["bound_planned"] - 1.0)
            if bounds.get("bound_planned", 0) > 0
            else float("nan")
        ),
        "gap_rounds": None if work.gap_rounds is None else work.gap_rounds.to_dict(),
        "sequence_method": seq.method,
        "sequence_cost": float(seq.cost),
        "sequence_history": [float(h) for h in seq.history],
        "sequence_start_cost": seq.start_cost,
        "sequence_engine": seq.params.get("engine"),
        "local_paths": local_stats,
        "seconds": {k: round(v, 6) for k, v in seconds.items()},
    }
