"""TSP solvers side by side for ``weldplan bench sequence``: ours and the peers, one interface.

Each solver is ``solve(D, seconds) -> (tour, wall seconds)`` on a closed TSP over the ``(n, n)``
distance matrix ``D`` (TSPLIB integer distances); the bench recomputes every length from the
returned tour itself (:func:`checked_length`), never from what a solver reports.

* ``ours`` -- :func:`~weldplan.optim.discrete.sequence.solve_sequence` with
  ``method="fast-tsp"`` (through :mod:`~weldplan.optim.discrete.tsp_engine`), ``seconds`` as
  its budget: the engine, measured against its peers. It has no seed, so the sequencer's
  default (``"auto"``) is nearest neighbour + the seeded polish above 13 nodes (the ``NN +
  polish`` column of the TSPLIB table).
* ``ours-1t`` -- the same engine with fast-tsp on one thread (``ours`` uses every core).
* ``pso+polish`` -- the paper's TSP-PSO (Table 4 parameters) + 2-opt / Or-opt iterated local
  search within ``seconds`` (the swarm's 100 iterations always run).
* ``fast-tsp`` -- ``fast_tsp.find_tour`` called directly on the integer matrix (a runtime
  dependency).
* ``lkh3`` -- LKH-3 through ``elkai`` (non-commercial licence: a benchmark peer only, installed
  by hand, never a dependency). elkai's public ``solve_tsp`` takes only ``RUNS``; the bench
  passes LKH's own ``TIME_LIMIT`` parameter through elkai's ``_elkai.solve_problem`` (the call
  ``solve_tsp`` makes), with ``RUNS = 1``. LKH's preprocessing (subgradient ascent for the
  alpha candidates) is outside ``TIME_LIMIT``: the measured wall time says what it took.
* ``ortools`` -- OR-Tools routing: default first solution + guided local search for ``seconds``
  (the ``bench`` extra).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from weldplan.optim.discrete.sequence import solve_sequence

Solver = Callable[[NDArray[np.float64], float], tuple[NDArray[np.intp], float]]


def checked_length(D: NDArray[np.float64], tour: NDArray[np.intp]) -> float:
    """Closed-tour length of ``tour`` over ``D``, after checking it visits every node once."""
    t = np.asarray(tour, dtype=np.intp).reshape(-1)
    n = D.shape[0]
    if len(t) == n + 1 and t[0] == t[-1]:
        t = t[:-1]
    if not np.array_equal(np.sort(t), np.arange(n)):
        raise ValueError(f"not a tour of {n} nodes (length {len(t)})")
    return float(D[t, np.roll(t, -1)].sum())


def ours(D: NDArray[np.float64], seconds: float) -> tuple[NDArray[np.intp], float]:
    t0 = time.perf_counter()
    s = solve_sequence(D, method="fast-tsp", closed=True, time_budget=seconds)
    return s.order_array, time.perf_counter() - t0


def ours_one_thread(D: NDArray[np.float64], seconds: float) -> tuple[NDArray[np.intp], float]:
    """``ours`` with fast-tsp on one thread (its own default): the engine on the closed tour
    through node 0, as ``solve_sequence`` calls it, to measure what the second core adds."""
    from weldplan.optim.discrete.tsp_engine import solve_fast_tsp

    t0 = time.perf_counter()
    res = solve_fast_tsp(D, 0, seconds=seconds, threads=1)
    return res.tour, time.perf_counter() - t0


def pso_polish(D: NDArray[np.float64], seconds: float) -> tuple[NDArray[np.intp], float]:
    t0 = time.perf_counter()
    s = solve_sequence(D, method="pso", closed=True, rng=0, time_budget=seconds)
    return s.order_array, time.perf_counter() - t0


def fast_tsp_direct(D: NDArray[np.float64], seconds: float) -> tuple[NDArray[np.intp], float]:
    import fast_tsp

    t0 = time.perf_counter()
    I = np.rint(D).astype(np.int64)
    t = fast_tsp.find_tour(I, float(seconds))
    return np.asarray(t, dtype=np.intp), time.perf_counter() - t0


def lkh3(D: NDArray[np.float64], seconds: float) -> tuple[NDArray[np.intp], float]:
    from elkai import _elkai

    t0 = time.perf_counter()
    n = D.shape[0]
    I = np.rint(D).astype(np.int64)
    params = f"RUNS = 1\nTIME_LIMIT = {seconds:g}\nPROBLEM_FILE = :stdin:\n"
    problem = (
        f"TYPE : TSP\nDIMENSION : {n}\nEDGE_WEIGHT_TYPE : EXPLICIT\n"
        "EDGE_WEIGHT_FORMAT : FULL_MATRIX\nEDGE_WEIGHT_SECTION\n"
        + "\n".join(" ".join(map(str, row)) for row in I.tolist())
        + "\n"
    )
    sol = _elkai.solve_problem(params, problem)
    return np.asarray(sol, dtype=np.intp) - 1, time.perf_counter() - t0


def ortools(D: NDArray[np.float64], seconds: float) -> tuple[NDArray[np.intp], float]:

    res = ortools_tour(D, seconds)
    if res is None:  # pragma: no cover - no solution within the limit
        raise RuntimeError("OR-Tools found no solution")
    return res


SOLVERS: dict[str, tuple[Solver, str | None]] = {
    "ours": (ours, None),
    "ours-1t": (ours_one_thread, None),
    "pso+polish": (pso_polish, None),
    "fast-tsp": (fast_tsp_direct, "fast_tsp"),
    "lkh3": (lkh3, "elkai"),
    "ortools": (ortools, "ortools"),
}


def available(name: str) -> bool:
    """Whether solver ``name``'s library imports here."""
    mod = SOLVERS[name][1]
    if mod is None:
        return True
    try:
        __import__(mod)
    except ImportError:
        return False
    return True


def ortools_tour(D: np.ndarray, seconds: float) -> tuple[np.ndarray, float] | None:
    """OR-Tools' default first solution + guided local search for ``seconds``; ``None`` when
    ``ortools`` is not importable. Returns the closed tour and the wall time (model included)."""
    try:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2
    except ImportError:
        return None
    t0 = time.perf_counter()
    n = D.shape[0]
    manager = pywrapcp.RoutingIndexManager(n, 1, 0)
    routing = pywrapcp.RoutingModel(manager)
    M = np.rint(D).astype(np.int64).tolist()
    if hasattr(routing, "RegisterTransitMatrix"):
        cb = routing.RegisterTransitMatrix(M)
    else:  # pragma: no cover - older OR-Tools

        def dist(i: int, j: int) -> int:
            return M[manager.IndexToNode(i)][manager.IndexToNode(j)]

        cb = routing.RegisterTransitCallback(dist)
    routing.SetArcCostEvaluatorOfAllVehicles(cb)
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.local_search_metaheuristic = (
        routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
    )
    params.time_limit.FromMilliseconds(int(seconds * 1000))
    sol = routing.SolveWithParameters(params)
    if sol is None:
        return None
    idx = routing.Start(0)
    tour = []
    while not routing.IsEnd(idx):
        tour.append(manager.IndexToNode(idx))
        idx = sol.Value(routing.NextVar(idx))
    return np.asarray(tour, dtype=np.intp), time.perf_counter() - t0
