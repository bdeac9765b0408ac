"""The sequencer's entry point: order nodes by a cost matrix, and the :class:`Sequence` result.

``solve_sequence(cost)`` orders the nodes of any ``(n, n)`` cost matrix (weld joints by their
collision-free path lengths, 2D goals by travel cost): an open path by default (a weld sequence
does not return), or a closed tour, optionally with a fixed first and/or last node. It knows
nothing about welding.

Methods
-------
``"exact"``
    Held-Karp (:mod:`~weldplan.optim.discrete.held_karp`): the optimum, up to about 20 nodes.
``"pso"``
    Clerc's discrete PSO with the paper's parameters (:mod:`~weldplan.optim.discrete.tsp_pso`),
    then, when ``polish`` is on, 2-opt + Or-opt iterated local search
    (:mod:`~weldplan.optim.discrete.local_search`). The result reports both costs.
``"nn"``
    Nearest-neighbour construction (best over start nodes, deterministic), then the same polish:
    seeded, budgeted by its number of kicks, so the same ``rng`` gives the same order on any
    machine.
``"fast-tsp"``
    fast-tsp's Lin-Kernighan-style local search (MIT; :mod:`~weldplan.optim.discrete.tsp_engine`
    wraps it: integer scaling with a reported rounding bound, the ATSP transform, ``inf`` pairs).
    Measured at LKH-3's level on TSPLIB up to 2,152 cities (docs/bench-sequence.md). It has no
    seed and cannot be given one: its Rust core draws its perturbations from ``fastrand``'s
    process-wide generator, seeded from fresh entropy in every process. Even with
    ``stop_when_converged`` and an infinite budget (no clock) and one thread, three runs on a280
    returned three different (optimal) tours, so its order is not reproducible and no polish
    after it can make it so. An explicit choice only.
``"auto"``
    ``"exact"`` up to :data:`EXACT_MAX_NODES` nodes, else ``"nn"``: every default order is
    reproducible (../shared/DESIGN.md). On TSPLIB with the default kicks, seed 0, ``"nn"`` ends
    0-1.5 % above the optimum, which fast-tsp reaches or nearly (kroA100 0 %, ch130 0 %, a280
    1.5 %, lin318 1.5 %), in 1-4 CPU s rather than tenths of one.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from typing import Any, TypedDict, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.optim.discrete.costs import (
    Reduction,
    check_cost,
    order_cost,
    penalised,
    reduce_to_tour,
)
from weldplan.optim.discrete.held_karp import MAX_NODES, held_karp_tour
from weldplan.optim.discrete.local_search import PolishParams
from weldplan.optim.discrete.local_search import polish as polish_tour
from weldplan.optim.discrete.tsp_pso import PSOParams, tsp_pso
from weldplan.options import laid_over
from weldplan.random import RNGLike, as_generator, seed_of

log = logging.getLogger(__name__)

#: ``method="auto"`` solves exactly up to this many nodes (Held-Karp takes milliseconds there).
EXACT_MAX_NODES = 13

METHODS = ("auto", "exact", "fast-tsp", "pso", "nn")


@dataclass(frozen=True)
class Sequence:
    """An ordering of the nodes of a cost matrix.

    Attributes
    ----------
    order
        Node indices (0-based) in visiting order; all ``n`` nodes once.
    cost
        Cost of ``order`` under the input matrix (closing edge included when ``closed``).
    method
        What produced it: ``"exact"``, ``"pso"``, ``"pso+polish"``, ``"nn"``, ``"nn+polish"``.
    closed, first, last
        The variant solved.
    history
        Best cost after initialisation and after each swarm iteration (empty for other methods);
        for convergence plots.
    evaluations
        Tours evaluated by the swarm (0 for other methods).
    seconds
        Wall time of the whole solve.
    seed
        The integer seed when one was given.
    start_cost
        Cost of the construction before polish (the PSO-alone or nearest-neighbour cost), or
        ``None`` when there was no polish.
    params
        The settings used (swarm and polish parameters).
    """

    order: tuple[int, ...]
    cost: float
    method: str
    closed: bool = False
    first: int | None = None
    last: int | None = None
    history: tuple[float, ...] = ()
    evaluations: int = 0
    seconds: float = 0.0
    seed: int | None = None
    start_cost: float | None = None
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def order_array(self) -> NDArray[np.intp]:
        return np.asarray(self.order, dtype=np.intp)

    def to_json(self) -> str:
        return json.dumps(asdict(self), allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> Sequence:
        d = json.loads(text)
        d["order"] = tuple(int(v) for v in d["order"])
        d["history"] = tuple(float(v) for v in d["history"])
        return cls(**d)


def resolve_method(method: str, n: int) -> str:
    """The method ``"auto"`` runs for ``n`` nodes (others unchanged): reproducible ones only."""
    if method == "auto":
        return "exact" if n <= EXACT_MAX_NODES else "nn"
    return method


def nearest_neighbour_tour(A: NDArray[np.float64], start: int, n_starts: int = 64) -> NDArray:
    """Best nearest-neighbour closed tour over ``A`` beginning ``start -> s`` over seeds ``s``.

    Every second node ``s`` (up to ``n_starts`` of them, evenly spread) seeds one greedy tour; all
    are built at once as arrays and the cheapest is returned. ``A`` must be finite.
    """
    m = A.shape[0]
    others = np.array([v for v in range(m) if v != start], dtype=np.intp)
    if len(others) <= 1:
        return np.concatenate([[start], others]).astype(np.intp)
    seeds = others[np.linspace(0, len(others) - 1, min(n_starts, len(others))).astype(np.intp)]
    R = len(seeds)
    rows = np.arange(R)
    visited = np.zeros((R, m), dtype=bool)
    visited[:, start] = True
    visited[rows, seeds] = True
    tours = np.empty((R, m), dtype=np.intp)
    tours[:, 0] = start
    tours[:, 1] = seeds
    cur = seeds
    for k in range(2, m):
        d = np.where(visited, np.inf, A[cur])
        nxt = np.argmin(d, axis=1)
        tours[:, k] = nxt
        visited[rows, nxt] = True
        cur = nxt
    costs = A[tours, np.roll(tours, -1, axis=1)].sum(axis=1)
    return tours[int(np.argmin(costs))]


def _no_finite_order(red: Reduction, exact: bool) -> PlanningError:
    A = red.A
    off = ~np.eye(red.m, dtype=bool)
    fin = np.isfinite(A) & off
    dead_out = [int(v) for v in np.flatnonzero(~fin.any(axis=1)) if v < red.n]
    dead_in = [int(v) for v in np.flatnonzero(~fin.any(axis=0)) if v < red.n]
    detail = []
    if dead_out:
        detail.append(f"nodes with no reachable successor: {dead_out}")
    if dead_in:
        detail.append(f"nodes no other node reaches: {dead_in}")
    what = "no order of finite cost exists" if exact else "found no order of finite cost"
    kind = "closed tour" if red.closed else "open path"
    ends = f" (first={red.first}, last={red.last})" if (red.first, red.last) != (None, None) else ""
    msg = f"sequencing {red.n} nodes as a {kind}{ends}: {what}"
    return PlanningError(msg + ("; " + "; ".join(detail) if detail else ""))


@dataclass(frozen=True)
class SequenceSettings:
    """What order :func:`solve_sequence` looks for and how it searches: one frozen object,
    validated once (../shared/DESIGN.md: a stage takes its inputs and one settings object).

    Attributes
    ----------
    method
        ``"auto"`` (exact up to :data:`EXACT_MAX_NODES` nodes, else ``"nn"``),
        ``"exact"``, ``"fast-tsp"``, ``"pso"`` or ``"nn"``; see the module docstring.
    closed
        Return to the first node (a tour) instead of an open path (the default for welding).
    first, last
        Node indices fixed at the start and/or end of the order (``last`` of a closed tour is the
        node visited before returning to ``first``); checked against the matrix when solving
        (a ``ValueError``).
    polish
        Run 2-opt + Or-opt iterated local search after ``"pso"`` / ``"nn"`` (ignored by
        ``"exact"``).
    pso
        Swarm settings; ``None``: :class:`PSOParams`, Table 4 of Wang et al. (2017).
    polish_params
        Polish settings; ``None``: :class:`PolishParams`.
    time_budget
        Seconds for the whole solve: the polish stops kicking when they are spent (and, unless
        ``polish_params.kicks`` is set, kicks until then). The swarm always runs its iterations.
        Results then depend on the machine's speed; leave it ``None`` for reproducible runs.
        For ``"fast-tsp"`` it is the wall budget of the whole call too: the engine searches
        for what the checks and the integer conversion leave of it (default
        :func:`~weldplan.optim.discrete.tsp_engine.default_seconds`: 1 ms a node), on every
        available core.
    """

    method: str = "auto"
    closed: bool = False
    first: int | None = None
    last: int | None = None
    polish: bool = True
    pso: PSOParams | None = None
    polish_params: PolishParams | None = None
    time_budget: float | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ConfigError(
                f"unknown method {self.method!r}; choose one of {METHODS}", field="method"
            )
        b = self.time_budget
        if b is not None and not (isinstance(b, (int, float)) and not isinstance(b, bool)):
            raise ConfigError(
                f"time_budget must be None or seconds, got {b!r}", field="time_budget"
            )

    @property
    def swarm(self) -> PSOParams:
        """The swarm's settings (:attr:`pso` or the paper's defaults)."""
        return PSOParams() if self.pso is None else self.pso

    @property
    def polishing(self) -> PolishParams:
        """The polish's settings (:attr:`polish_params` or the defaults)."""
        return PolishParams() if self.polish_params is None else self.polish_params


class SequenceOptions(TypedDict, total=False):
    """The keyword conveniences of :func:`solve_sequence`: any field of
    :class:`SequenceSettings` by name, laid over the ``settings`` given."""

    method: str
    closed: bool
    first: int | None
    last: int | None
    polish: bool
    pso: PSOParams | None
    polish_params: PolishParams | None
    time_budget: float | None


def solve_sequence(
    cost: ArrayLike,
    settings: SequenceSettings | None = None,
    *,
    rng: RNGLike = None,
    callback: Callable[[int, float], bool | None] | None = None,
    initial: ArrayLike | None = None,
    avoid: ArrayLike | None = None,
    **options: Unpack[SequenceOptions],
) -> Sequence:
    """Order the nodes of ``cost`` to minimise the total cost.

    Parameters
    ----------
    cost
        ``(n, n) float``: ``cost[i, j]`` of going from node ``i`` to node ``j`` (mm of path in the
        weld pipeline). May be asymmetric; ``inf`` marks an unreachable pair; NaN is an error.
    settings
        The order wanted and the search (:class:`SequenceSettings`: method, open or closed,
        fixed first / last node, polish, swarm and polish parameters, time budget); ``None``:
        the defaults (an open path, ``"auto"``).
    rng
        Seed or Generator for the swarm and the kicks.
    callback
        ``callback(iteration, best_cost)`` from the swarm; return ``True`` to stop it early.
    initial
        ``(n,) int`` a visiting order to start from (a warm start, e.g. the previous order after
        a few costs changed): the swarm / nearest-neighbour construction is skipped and only the
        polish runs from it (``method`` is then reported as ``"warm+polish"``). Ignored by
        ``"exact"``; with ``polish=False`` the order is returned as given. ``"fast-tsp"`` has
        no warm start and ignores it (and ``polish``: its own search is the polish).
    avoid
        ``(n, n) bool``: pairs to use only where no order does without them (the pipeline's legs
        not planned yet). ``"fast-tsp"`` prices them above every other finite cost; ``"pso"`` /
        ``"nn"`` add a penalty larger than any order over the other pairs. The returned ``cost``
        is over ``cost`` itself; ``params["avoided_edges"]`` counts those the order uses.
        Ignored by ``"exact"``.
    **options
        Any field of :class:`SequenceSettings` by name (``method="exact"``, ``closed=True``,
        ``first=0``...), laid over ``settings``: ``solve_sequence(C, method="exact")`` is
        ``solve_sequence(C, SequenceSettings(method="exact"))``.

    Returns
    -------
    Sequence

    Raises
    ------
    PlanningError
        When no order of finite cost exists (or none was found by a heuristic on an instance too
        large to settle exactly).
    ValueError
        For a malformed matrix or bad ``first`` / ``last``; a
        :class:`~weldplan.errors.ConfigError` (a ``ValueError``) naming the field for a bad
        setting (an unknown method...).
    TypeError
        For a keyword that is not a settings field.
    """
    t0 = time.perf_counter()
    st = laid_over(SequenceSettings, settings, options, "solve_sequence")
    C = check_cost(cost)
    n = C.shape[0]
    closed, first, last = st.closed, st.first, st.last
    red = reduce_to_tour(C, closed, first, last)
    gen = as_generator(rng)
    seed = seed_of(rng)
    pp = st.polishing
    method = resolve_method(st.method, n)
    av = _reduced_avoid(avoid, n, red.m)
    if method == "exact" and red.m > MAX_NODES:
        raise ValueError(
            f"method='exact' handles at most {MAX_NODES - 1} nodes for an open path and "
            f"{MAX_NODES} for a closed tour (memory grows as 8 n 2^n bytes); got {n}"
        )

    history: tuple[float, ...] = ()
    evaluations = 0
    start_cost: float | None = None
    params: dict[str, Any] = {}
    if method == "exact":
        tour, best = held_karp_tour(red.A, red.start)
        if not np.isfinite(best):
            raise _no_finite_order(red, exact=True)
        name = "exact"
    elif method == "fast-tsp":
        budget = st.time_budget
        left = None if budget is None else max(0.0, budget - (time.perf_counter() - t0))
        tour, params = _fast_tsp(red, left, av, pp, gen)
        name = "fast-tsp"
    else:
        deadline = None if st.time_budget is None else t0 + st.time_budget
        tour, name, history, evaluations, start_cost = _heuristic(
            C, red, st, method, initial, av, gen, callback, params, deadline
        )
    if name != "exact" and not np.isfinite(order_cost(red.A, tour, True)):
        tour, name = _exact_fallback(red)
    order = red.to_order(tour)
    total = order_cost(C, order, closed)
    if av is not None:
        params["avoided_edges"] = int(av[tour, np.roll(tour, -1)].sum())
    seconds = time.perf_counter() - t0
    log.info("sequenced %d nodes with %s: cost %.6g in %.3f s", n, name, total, seconds)
    return Sequence(
        order=tuple(int(v) for v in order),
        cost=total,
        method=name,
        closed=closed,
        first=first,
        last=last,
        history=history,
        evaluations=evaluations,
        seconds=seconds,
        seed=seed,
        start_cost=start_cost,
        params=params,
    )


def _heuristic(C, red, st, method, initial, av, gen, callback, params, deadline):
    """The paper's swarm (or nearest neighbour, or a warm start), then the polish, as ``st``
    (a :class:`SequenceSettings`) asks; ``method`` is ``st.method`` resolved (``"pso"`` or
    ``"nn"``).

    Returns ``(tour, name, history, evaluations, start_cost)`` on the reduced matrix; fills
    ``params`` with the swarm's and the polish's settings. ``deadline``: the
    ``time.perf_counter()`` at which the whole solve's budget ends (None: no budget); the
    polish gets what the swarm leaves of it.
    """
    pso, pp, closed = st.swarm, st.polishing, st.closed
    n = C.shape[0]
    history: tuple[float, ...] = ()
    evaluations = 0
    start_cost: float | None = None
    Ap, _ = penalised(red.A)
    if av is not None:
        Ap = Ap + np.where(av, _avoid_penalty(Ap, av), 0.0)
    if initial is not None:
        init = np.asarray(initial, dtype=np.intp).reshape(-1)
        if not np.array_equal(np.sort(init), np.arange(n)):
            raise ValueError(f"initial must be a permutation of 0..{n - 1}")
        tour = red.to_tour(init)
        method = "warm"
    elif method == "pso":
        res = tsp_pso(Ap, red.start, pso, gen, callback)
        tour, history, evaluations = res.tour, res.history, res.evaluations
        params["pso"] = pso.to_dict()
    else:
        tour = nearest_neighbour_tour(Ap, red.start)
    name = method
    if st.polish:
        start_cost = order_cost(C, red.to_order(tour), closed)
        if deadline is not None:
            pp = replace(pp, time_budget=max(0.0, deadline - time.perf_counter()))
        tour, _, stats = polish_tour(Ap, tour, pp, gen)
        params["polish"] = pp.to_dict()
        params["polish_stats"] = stats
        name += "+polish"
    return tour, name, history, evaluations, start_cost


def _exact_fallback(red):
    """A heuristic order of infinite cost: settle it exactly where Held-Karp can, else fail."""
    if red.m <= EXACT_MAX_NODES + 1:
        tour, best = held_karp_tour(red.A, red.start)
        if np.isfinite(best):
            return tour, "exact"
        raise _no_finite_order(red, exact=True)
    raise _no_finite_order(red, exact=False)


def _reduced_avoid(avoid: ArrayLike | None, n: int, m: int) -> NDArray[np.bool_] | None:
    """The ``avoid`` mask on the reduced ``(m, m)`` matrix (dummy-node edges never avoided)."""
    if avoid is None:
        return None
    a = np.asarray(avoid, dtype=bool)
    if a.shape != (n, n):
        raise ValueError(f"avoid must be ({n}, {n}), got shape {a.shape}")
    out = np.zeros((m, m), dtype=bool)
    out[:n, :n] = a
    np.fill_diagonal(out, False)
    return out if out.any() else None


def _avoid_penalty(Ap: NDArray[np.float64], avoid: NDArray[np.bool_]) -> float:
    """A penalty above any tour over the pairs not avoided (``m`` edges each at most the max)."""
    other = Ap[~avoid]
    return Ap.shape[0] * float(other.max() if len(other) else 1.0) + 1.0


def _fast_tsp(
    red: Reduction,
    seconds: float | None,
    avoid: NDArray[np.bool_] | None,
    pp: PolishParams,
    gen: np.random.Generator,
) -> tuple[NDArray[np.intp], dict[str, Any]]:
    """fast-tsp on the reduction; an order it returns through an ``inf`` pair (or an ATSP tour
    that does not alternate) is handed to the 2-opt / Or-opt polish over the penalised matrix
    before :func:`solve_sequence` gives up on it."""
    from weldplan.optim.discrete.tsp_engine import search_threads, solve_fast_tsp

    res = solve_fast_tsp(red.A, red.start, seconds=seconds, avoid=avoid)
    params: dict[str, Any] = {
        "engine": {
            "solver": "fast-tsp",
            "transform": res.transform,
            "scale": res.scale,
            "cap": res.cap,
            "rounding_bound": res.rounding_bound,
            "optimality_loss_bound": res.optimality_loss_bound,
            "clipped_edges": res.clipped_edges,
            "penalty_edges": res.penalty_edges,
            "feasible": res.feasible,
            "seconds": res.seconds,
            "threads": search_threads(),
        }
    }
    tour = res.tour
    if res.penalty_edges or not res.feasible:
        log.warning(
            "fast-tsp returned an order through %d unreachable pairs%s; polishing it",
            res.penalty_edges,
            "" if res.feasible else " (ATSP tour not alternating)",
        )
        Ap, _ = penalised(red.A)
        if avoid is not None:
            Ap = Ap + np.where(avoid, _avoid_penalty(Ap, avoid), 0.0)
        tour, _, stats = polish_tour(Ap, tour, replace(pp, kicks=pp.kicks or 0), gen)
        params["engine"]["repaired_by_polish"] = True
    return tour, params
