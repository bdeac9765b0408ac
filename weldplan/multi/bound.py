"""A proved lower bound of the station cycle time, printed beside every allocation.

Issue 30 asks for a bound of at least ``max(LP relaxation, unavoidable single-robot time)``.
:func:`lower_bound` returns the larger of two bounds, each valid for any assignment of the
served welds and any visiting orders:

``lp``: **the min-max assignment with tour shares, relaxed.** Robot ``r``'s cycle over its welds
``S`` is its weld times plus a route over ``S``, and the route costs at least
``sum_S share_ri - slack_r`` (:func:`weldplan.multi.problem.tour_shares`), and at least 0. So
with ``x_ri = 1`` when ``r`` welds ``i``, every allocation satisfies

    sum_i x_ri (w_ri + share_ri) - slack_r <= C,   sum_i x_ri w_ri <= C,   sum_r x_ri = 1

for its cycle ``C``; the least ``C`` over ``x`` in ``[0, 1]`` (the LP relaxation, solved by
HiGHS through :func:`scipy.optimize.linprog`) is at most the least over ``x`` in ``{0, 1}``,
which is at most the optimum. The weld-time constraint gives the issue's "total weld time / R"
term (and more: each weld at its cheapest robot).

``unique``: **the welds only one robot serves.** Robot ``r`` welds all of ``U_r`` whatever the
allocation: its cycle is at least their weld times plus a route over a superset of ``U_r``. When
its move times satisfy the triangle inequality (checked, :func:`is_metric`), shortcutting the
other welds gives a route over ``U_r`` alone that is no longer, so the optimal route over
``U_r`` bounds it: Held-Karp up to :data:`UNIQUE_EXACT_MAX` welds, the 1-tree bound
(:func:`weldplan.optim.discrete.bounds.one_tree_bound`) above for symmetric times. Otherwise (or
when better) the shares of ``U_r`` bound it as above. Leg-time *bounds* between welds
(:mod:`weldplan.robot.legtime`) minimise over configurations per pair, which can break the
triangle inequality, hence the check.

Spensieri et al. (IEEE T-ASE 2016) bound the min-max multiple generalised TSP the same way in
spirit (a relaxation of the assignment with per-node tour costs); the shares here are the
classic degree argument of the 1-tree / assignment bounds of the TSP.
"""

from __future__ import annotations

import logging

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import PlanningError
from weldplan.multi.problem import AllocationProblem
from weldplan.multi.result import LowerBound

log = logging.getLogger(__name__)

#: Held-Karp bounds the route over a robot's unique welds up to this many (milliseconds)
UNIQUE_EXACT_MAX = 12
#: relative tolerance of the triangle-inequality check
METRIC_RTOL = 1e-9
#: subgradient steps of the 1-tree bound (a work budget, not a clock)
ONE_TREE_ITER = 300


def is_metric(T: NDArray[np.float64]) -> bool:
    """Whether ``T (n, n)`` satisfies ``T[i, k] <= T[i, j] + T[j, k]`` for all ``i, j, k``
    (up to :data:`METRIC_RTOL` of its largest entry); ``O(n^3)`` in ``n`` numpy steps."""
    n = len(T)
    tol = METRIC_RTOL * float(T.max(initial=0.0))
    return all(bool(np.all(T[:, j, None] + T[None, j, :] >= T - tol)) for j in range(n))


def assignment_model(
    problem: AllocationProblem, cost: NDArray[np.float64], slack: NDArray[np.float64] | None
) -> tuple[NDArray[np.intp], NDArray[np.intp], tuple]:
    """The min-max assignment over the served pairs as arrays for HiGHS.

    Variables: ``x_k`` for each pair ``(rob[k], weld[k])`` the reach map allows, then ``C``.
    Minimise ``C`` subject to ``sum_r x_ri = 1`` per served weld and, per robot,
    ``sum_i cost_ri x_ri - C <= slack_r`` (and ``sum_i w_ri x_ri - C <= 0`` when ``slack`` is
    given: the bound's weld-time rows).

    Returns
    -------
    rob, weld, (c, A_ub, b_ub, A_eq, b_eq)
        ``(K,)`` pair indices and the model (sparse matrices).
    """
    from scipy.sparse import coo_matrix

    ok = problem.ok
    R, W = ok.shape
    rob, weld = np.nonzero(ok)
    K = len(rob)
    c = np.zeros(K + 1)
    c[K] = 1.0
    served = np.flatnonzero(ok.any(axis=0))
    row_of = np.full(W, -1)
    row_of[served] = np.arange(len(served))
    A_eq = coo_matrix((np.ones(K), (row_of[weld], np.arange(K))), shape=(len(served), K + 1))
    rows = [rob, np.arange(R)]
    cols = [np.arange(K), np.full(R, K)]
    vals = [cost[rob, weld], -np.ones(R)]
    b_ub = np.zeros(R) if slack is None else np.asarray(slack, dtype=np.float64)
    n_rows = R
    if slack is not None:
        rows += [R + rob, R + np.arange(R)]
        cols += [np.arange(K), np.full(R, K)]
        vals += [problem.weld_time[rob, weld], -np.ones(R)]
        b_ub = np.concatenate([b_ub, np.zeros(R)])
        n_rows = 2 * R
    A_ub = coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(n_rows, K + 1),
    )
    return rob, weld, (c, A_ub.tocsr(), b_ub, A_eq.tocsr(), np.ones(len(served)))


def lp_bound(problem: AllocationProblem) -> float:
    """s: the ``lp`` term of the module docstring (0 when no weld is served)."""
    from scipy.optimize import linprog

    if not problem.served.any():
        return 0.0
    cost = problem.weld_time + problem.share
    _, _, (c, A_ub, b_ub, A_eq, b_eq) = assignment_model(problem, cost, problem.slack)
    bounds = [(0.0, 1.0)] * (len(c) - 1) + [(0.0, None)]
    res = linprog(c, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status != 0:
        raise PlanningError(f"the allocation bound's LP failed: {res.message}")
    # HiGHS's dual bound is its objective up to its tolerance (1e-7 on each row): stay below
    return max(0.0, float(res.fun) - 1e-7 * max(1.0, abs(float(res.fun))))


def _route_bound(problem: AllocationProblem, r: int, U: NDArray[np.intp]) -> tuple[float, str]:
    """s: a lower bound of robot ``r``'s route over any superset of ``U`` it serves."""
    shares = max(0.0, float(problem.share[r, U].sum() - problem.slack[r]))
    if len(U) < 2:
        return shares, "shares"
    idx = np.flatnonzero(problem.ok[r])
    T = problem.travel[r]
    if not is_metric(T[np.ix_(idx, idx)]):
        return shares, "shares"
    M = T[np.ix_(U, U)]
    if len(U) <= UNIQUE_EXACT_MAX:
        from weldplan.optim.discrete.sequence import solve_sequence

        tour = float(solve_sequence(M, method="exact", closed=problem.closed).cost)
        return max(shares, tour), "held-karp"
    if np.allclose(M, M.T):
        from weldplan.optim.discrete.bounds import one_tree_bound

        t = float(one_tree_bound(M, open_path=not problem.closed, max_iter=ONE_TREE_ITER))
        return max(shares, t), "1-tree"
    return shares, "shares"


def lower_bound(problem: AllocationProblem) -> LowerBound:
    """The :class:`~weldplan.multi.result.LowerBound` of ``problem`` (module docstring)."""
    lp = lp_bound(problem)
    ok = problem.ok
    single = ok.sum(axis=0) == 1
    unique, who, how = 0.0, "", ""
    for r in range(ok.shape[0]):
        U = np.flatnonzero(single & ok[r])
        if not len(U):
            continue
        route, method = _route_bound(problem, r, U)
        t = float(problem.weld_time[r, U].sum()) + route
        if t > unique:
            unique, who, how = t, problem.reach.robots[r], method
    lp_name = "LP relaxation of the min-max assignment with tour shares"
    uq_name = f"unique-reach welds of {who} ({how})" if who else "unique-reach welds"
    name = f"max({lp_name}, {uq_name})" if lp >= unique else f"max({uq_name}, {lp_name})"
    log.info(
        "allocation lower bound %.3f s (LP %.3f s, unique-reach %.3f s)",
        max(lp, unique),
        lp,
        unique,
    )
    return LowerBound(max(lp, unique), name, lp, unique, who, how)
