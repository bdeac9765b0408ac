"""A proved lower bound of the station cycle time, printed beside every allocation.

Issue 30 asks for a bound of at least ``max(LP relaxation, unavoidable single-robot time)``.
:func:`lower_bound` returns the larger of two bounds, each valid for any assignment of the
served welds and any visiting orders:

``lp``: **the min-max assignment with tour shares, relaxed.** Robot ``r``'s cycle over its welds
``S`` is its weld times plus a route over ``S``, and the route costs at least
``sum_S share_ri - slack_r`` (:func:`weldplan.multi.problem.tour_shares`), and at least 0. So
with ``x_ri = 1`` when ``r`` welds ``i``, every allocation satisfies

    sum_i x_ri (w_ri + share_ri) - slack_r <= C,   sum_i x_ri w_ri <= C,   sum_r x_ri = 1

(for closed tours the slack is needed only by a robot with a single weld:
:func:`assignment_model` pays it only there)
for its cycle ``C``; the least ``C`` over ``x`` in ``[0, 1]`` (the LP relaxation, solved by
HiGHS through :func:`scipy.optimize.linprog`) is at most the least over ``x`` in ``{0, 1}``,
which is at most the optimum. The weld-time constraint gives the issue's "total weld time / R"
term (and more: each weld at its cheapest robot).

``integer``: **the same assignment in integers**, by HiGHS's branch and bound
(:func:`scipy.optimize.milp`, budgeted by nodes): its *dual bound*, the least value any integer
assignment can still reach when the search stops, bounds the integer optimum of the model
above, hence the station's optimum; it is never below the LP (up to HiGHS's tolerances) and,
on small stations where the LP splits welds between robots, often well above it.

``unique``: **the welds only one robot serves.** Robot ``r`` welds all of ``U_r`` whatever the
allocation: its cycle is at least their weld times plus a route over a superset of ``U_r``. When
its move times satisfy the triangle inequality (checked, :func:`is_metric`), shortcutting the
other welds gives a route over ``U_r`` alone that is no longer, so the optimal route over
``U_r`` bounds it: Held-Karp up to :data:`UNIQUE_EXACT_MAX` welds, the 1-tree bound
(:func:`weldplan.optim.discrete.bounds.one_tree_bound`) above for symmetric times. Otherwise (or
when better) the shares of ``U_r`` bound it as above. Leg-time *bounds* between welds
(:mod:`weldplan.robot.route.legtime`) minimise over configurations per pair, which can break the
triangle inequality, hence the check.

Spensieri et al. (IEEE T-ASE 2016) bound the min-max multiple generalised TSP the same way in
spirit (a relaxation of the assignment with per-node tour costs); the shares here are the
classic degree argument of the 1-tree / assignment bounds of the TSP.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.multi.problem import AllocationProblem
from weldplan.multi.result import LowerBound

log = logging.getLogger(__name__)

#: Held-Karp bounds the route over a robot's unique welds up to this many (milliseconds)
UNIQUE_EXACT_MAX = 12
#: relative tolerance of the triangle-inequality check
METRIC_RTOL = 1e-9
#: subgradient steps of the 1-tree bound (a work budget, not a clock)
ONE_TREE_ITER = 300
#: branch-and-bound nodes of the ``integer`` term, and its wall-clock safety net (s)
DEFAULT_NODES = 500
DEFAULT_SECONDS = 60.0
#: HiGHS's primal feasibility tolerance (relative), taken off its values to stay below them
HIGHS_TOL = 1e-7


def is_metric(T: NDArray[np.float64]) -> bool:
    """Whether ``T (n, n)`` satisfies ``T[i, k] <= T[i, j] + T[j, k]`` for all ``i, j, k``
    (up to :data:`METRIC_RTOL` of its largest entry); ``O(n^3)`` in ``n`` numpy steps."""
    n = len(T)
    tol = METRIC_RTOL * float(T.max(initial=0.0))
    return all(bool(np.all(T[:, j, None] + T[None, j, :] >= T - tol)) for j in range(n))


@dataclass(frozen=True, eq=False)
class AssignmentModel:
    """The min-max assignment of :func:`assignment_model` as arrays for HiGHS.

    Attributes
    ----------
    rob, weld
        ``(K,)``: the robot and weld of each assignment variable ``x_k``.
    c
        ``(n,)``: the objective (``C``, the cycle, is variable ``K``).
    A_ub, b_ub, A_eq, b_eq
        The constraints (sparse CSR).
    upper, integrality
        ``(n,)``: each variable's upper bound (lower: 0) and integrality (1: binary).
    """

    rob: NDArray[np.intp]
    weld: NDArray[np.intp]
    c: NDArray[np.float64]
    A_ub: Any
    b_ub: NDArray[np.float64]
    A_eq: Any
    b_eq: NDArray[np.float64]
    upper: NDArray[np.float64]
    integrality: NDArray[np.float64]

    def milp(self, options: dict[str, Any]) -> Any:
        """HiGHS's branch and bound on this model (:func:`scipy.optimize.milp` with
        ``options``: its node limit, gap, clock safety net), its ``OptimizeResult``."""
        from scipy.optimize import Bounds, LinearConstraint, milp

        return milp(
            self.c,
            constraints=[
                LinearConstraint(self.A_ub, -np.inf, self.b_ub),
                LinearConstraint(self.A_eq, self.b_eq, self.b_eq),
            ],
            integrality=self.integrality,
            bounds=Bounds(0.0, self.upper),
            options=options,
        )


def assignment_model(
    problem: AllocationProblem,
    cost: NDArray[np.float64],
    *,
    bound: bool,
    home: NDArray[np.float64] | None = None,
) -> AssignmentModel:
    """The min-max assignment over the served pairs.

    Variables: ``x_k`` for each pair ``(rob[k], weld[k])`` the reach map allows, then ``C``.
    Minimise ``C`` subject to ``sum_r x_ri = 1`` per served weld and, per robot,
    ``sum_i cost_ri x_ri - C <= 0``. With ``bound`` (the module docstring's model): the
    robot's :attr:`~weldplan.multi.problem.AllocationProblem.slack` on the right, and
    ``sum_i w_ri x_ri - C <= 0``; for closed tours the slack is only needed by a robot with
    one weld, so it is ``slack_r y_r`` with a binary ``y_r`` that allows at most one weld
    (``sum_i x_ri + (n_r - 1) y_r <= n_r``, ``n_r`` the welds ``r`` serves).

    ``home`` (``(R, W)`` s, with ``bound``): each robot's route starts and ends at its home,
    ``home[r, i]`` a lower bound of the leg between its home and weld ``i`` (either way). The
    route is then a closed tour over its welds and its home, and the degree argument of
    :func:`~weldplan.multi.problem.tour_shares` holds with the home as one more node
    (:func:`home_shares`): ``sum_i x_ri (w_ri + share_ri) + h_r y_r <= C`` with ``y_r >= x_ri``
    (``y_r``: the robot welds at all; binary) and no slack, a robot with no weld costing 0.
    """
    if bound and home is not None:
        return _home_model(problem, cost, home)
    from scipy.sparse import coo_matrix

    ok = problem.ok
    R, W = ok.shape
    rob, weld = np.nonzero(ok)
    K = len(rob)
    ys = bound and problem.closed
    n = K + 1 + (R if ys else 0)
    c = np.zeros(n)
    c[K] = 1.0
    served = np.flatnonzero(ok.any(axis=0))
    row_of = np.full(W, -1)
    row_of[served] = np.arange(len(served))
    A_eq = coo_matrix((np.ones(K), (row_of[weld], np.arange(K))), shape=(len(served), n))
    rr, xs, CC = np.arange(R), np.arange(K), np.full(R, K)
    rows, cols, vals = [rob, rr], [xs, CC], [cost[rob, weld], -np.ones(R)]
    b_ub = np.zeros(R)
    if bound:
        rows += [R + rob, R + rr]
        cols += [xs, CC]
        vals += [problem.weld_time[rob, weld], -np.ones(R)]
        b_ub = np.r_[np.zeros(R) if ys else problem.slack, np.zeros(R)]
    if ys:
        n_r = ok.sum(axis=1).astype(np.float64)
        rows += [rr, 2 * R + rob, 2 * R + rr]
        cols += [K + 1 + rr, xs, K + 1 + rr]
        vals += [-problem.slack, np.ones(K), n_r - 1.0]
        b_ub = np.r_[b_ub, n_r]
    A_ub = coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(len(b_ub), n),
    )
    upper = np.ones(n)
    upper[K] = np.inf
    integrality = np.ones(n)
    integrality[K] = 0.0
    return AssignmentModel(
        rob, weld, c, A_ub.tocsr(), b_ub, A_eq.tocsr(), np.ones(len(served)), upper, integrality
    )


def home_shares(
    problem: AllocationProblem, home: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``((R, W) s, (R,) s)``: each weld's share of a closed tour through the robot's home
    (the cheapest way out of it and the cheapest way in, over the other welds it serves and
    the home, halved) and the home's share (its cheapest leg, out and back: each of its two
    legs is at least that); ``home (R, W)`` s as in :func:`assignment_model`."""
    ok = problem.ok
    R, W = ok.shape
    share, hs = np.zeros((R, W)), np.zeros(R)
    for r in range(R):
        idx = np.flatnonzero(ok[r])
        if not len(idx):
            continue
        M = problem.travel[r][np.ix_(idx, idx)].astype(np.float64, copy=True)
        np.fill_diagonal(M, np.inf)
        h = np.asarray(home[r], dtype=np.float64)[idx]
        out_ = np.minimum(M.min(axis=1, initial=np.inf), h)
        in_ = np.minimum(M.min(axis=0, initial=np.inf), h)
        share[r, idx] = (out_ + in_) / 2.0
        hs[r] = float(h.min())
    return share, hs


def _home_model(
    problem: AllocationProblem, cost: NDArray[np.float64], home: NDArray[np.float64]
) -> AssignmentModel:
    """:func:`assignment_model` with ``bound`` and ``home``: variables ``x_k``, ``C``, ``y_r``.
    ``cost`` is not read (the shares through the home replace the tour shares)."""
    from scipy.sparse import coo_matrix

    ok = problem.ok
    R, W = ok.shape
    rob, weld = np.nonzero(ok)
    K = len(rob)
    n = K + 1 + R
    c = np.zeros(n)
    c[K] = 1.0
    served = np.flatnonzero(ok.any(axis=0))
    row_of = np.full(W, -1)
    row_of[served] = np.arange(len(served))
    A_eq = coo_matrix((np.ones(K), (row_of[weld], np.arange(K))), shape=(len(served), n))
    share, hs = home_shares(problem, home)
    rr, xs, ys, CC = np.arange(R), np.arange(K), K + 1 + np.arange(R), np.full(R, K)
    wt = problem.weld_time[rob, weld]
    rows = [rob, rr, rr, R + rob, R + rr, 2 * R + xs, 2 * R + xs]
    cols = [xs, ys, CC, xs, CC, xs, ys[rob]]
    vals = [wt + share[rob, weld], hs, -np.ones(R), wt, -np.ones(R), np.ones(K), -np.ones(K)]
    A_ub = coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(2 * R + K, n),
    )
    upper = np.ones(n)
    upper[K] = np.inf
    integrality = np.ones(n)
    integrality[K] = 0.0
    return AssignmentModel(
        rob, weld, c, A_ub.tocsr(), np.zeros(2 * R + K), A_eq.tocsr(), np.ones(len(served)),
        upper, integrality,
    )  # fmt: skip


def _below(v: float) -> float:
    """``v`` less HiGHS's feasibility tolerance (1e-7 on each row, relative): stay below."""
    return max(0.0, float(v) - HIGHS_TOL * max(1.0, abs(float(v))))


def assignment_bounds(
    problem: AllocationProblem,
    nodes: int = DEFAULT_NODES,
    seconds: float = DEFAULT_SECONDS,
    home: NDArray[np.float64] | None = None,
) -> tuple[float, float, str]:
    """``(lp, integer, status)``: the ``lp`` and ``integer`` terms of the module docstring
    (s; 0 when no weld is served) and HiGHS's word on the integer search (``nodes``:
    its branch-and-bound budget; ``seconds``: a wall-clock safety net, reported in
    ``status`` when it fires; ``home``: :func:`assignment_model`)."""
    from scipy.optimize import linprog

    if not problem.served.any():
        return 0.0, 0.0, "no weld served"
    m = assignment_model(problem, problem.weld_time + problem.share, bound=True, home=home)
    bounds = [(0.0, None if np.isinf(u) else u) for u in m.upper]
    res = linprog(
        m.c, A_ub=m.A_ub, b_ub=m.b_ub, A_eq=m.A_eq, b_eq=m.b_eq, bounds=bounds, method="highs"
    )
    if res.status != 0:
        raise PlanningError(f"the allocation bound's LP failed: {res.message}")
    lp = _below(res.fun)
    mres = m.milp({"node_limit": nodes, "mip_rel_gap": 0.0, "time_limit": seconds})
    dual = getattr(mres, "mip_dual_bound", None)
    if dual is None or not np.isfinite(dual):
        return lp, 0.0, str(mres.message)
    return lp, _below(dual), str(mres.message)


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


def lower_bound(
    problem: AllocationProblem,
    *,
    nodes: int = DEFAULT_NODES,
    seconds: float = DEFAULT_SECONDS,
    home: ArrayLike | None = None,
) -> LowerBound:
    """The :class:`~weldplan.multi.result.LowerBound` of ``problem`` (module docstring;
    ``nodes``, ``seconds``: :func:`assignment_bounds`).

    ``home``: ``(R, W)`` s, each robot's legs between its home and each weld bounded below
    (:attr:`PoseFreeLegs.home`) when every robot starts and ends its cycle at its home: the
    assignment terms then close each robot's route through its home (:func:`assignment_model`)
    and the unique-reach term adds its cheapest leg out and back."""
    H = None if home is None else np.asarray(home, dtype=np.float64)
    if H is not None:
        if H.shape != problem.ok.shape or not np.all(np.isfinite(H) & (H >= 0)):
            raise ConfigError(
                f"must be {problem.ok.shape} s, finite and >= 0, got {H.shape}", field="home"
            )
        H = np.where(problem.ok, H, 0.0)
    lp, integer, status = assignment_bounds(problem, nodes, seconds, H)
    ok = problem.ok
    single = ok.sum(axis=0) == 1
    unique, who, how = 0.0, "", ""
    for r in range(ok.shape[0]):
        U = np.flatnonzero(single & ok[r])
        if not len(U):
            continue
        route, method = _route_bound(problem, r, U)
        if H is not None:  # out of home to some weld it serves, and back
            route += 2.0 * float(H[r, ok[r]].min())
        t = float(problem.weld_time[r, U].sum()) + route
        if t > unique:
            unique, who, how = t, problem.reach.robots[r], method
    shares = "tour shares" if H is None else "tour shares through each robot's home"
    terms = {
        f"min-max assignment with {shares} (HiGHS dual bound)": integer,
        "its LP relaxation": lp,
        f"unique-reach welds of {who} ({how})" if who else "unique-reach welds": unique,
    }
    names = sorted(terms, key=lambda k: -terms[k])  # the binding term first
    value = max(terms.values())
    log.info(
        "allocation lower bound %.3f s (integer %.3f s, LP %.3f s, unique-reach %.3f s)",
        value,
        integer,
        lp,
        unique,
    )
    return LowerBound(value, f"max({', '.join(names)})", lp, unique, who, how, integer, status)


#: bisection steps of :func:`tcp_leg_bound` (each halves the bracket; 60 reach float precision)
TCP_BISECTIONS = 60


def lever_arms(opw: Any, tcp_mm: float) -> NDArray[np.float64]:
    """``(6,)`` mm: for each joint of an OPW arm (Brandstötter et al. 2014, figure 1: axis 1
    vertical through the base, joint 2 at ``(a1, b, c1)`` on it, ``c2`` to joint 3, the wrist
    centre ``sqrt(a2^2 + c3^2)`` beyond, the flange ``c4`` beyond that) an upper bound of the
    distance from its axis to a TCP ``tcp_mm`` from the flange, in every configuration: the
    sum of the link lengths from a point of the axis to the TCP (axes 4 and 5 pass through the
    wrist centre, axis 6 through the flange)."""
    t = abs(float(tcp_mm))
    l5 = float(opw.c4) + t
    l3 = float(np.hypot(opw.a2, opw.c3)) + l5
    l2 = float(opw.c2) + l3
    l1 = float(np.hypot(opw.a1, opw.b)) + l2
    return np.array([l1, l2, l3, l5, l5, t])


def tcp_leg_bound(
    positions: Any, lever: Any, velocity: Any, acceleration: Any
) -> NDArray[np.float64]:
    """``(W, W)`` s: a lower bound of any rest-to-rest motion that takes the TCP from weld ``i``
    to weld ``j`` (``positions (W, 3)`` mm), whatever the gun pose, IK branch and path.

    The argument: a revolute joint ``k`` turning at ``q'_k`` moves the TCP at most
    ``|q'_k| L_k`` (``L_k = lever[k]``, :func:`lever_arms`), so the TCP's path is at most
    ``sum_k L_k int |q'_k| dt``. Starting and ending at rest with ``|q'_k| <= v_k`` and
    ``|q''_k| <= a_k``, ``|q'_k(t)| <= min(v_k, a_k t, a_k (T - t))``, whose integral is
    ``D_k(T) = a_k T^2 / 4`` (``T <= 2 v_k / a_k``) or ``v_k T - v_k^2 / a_k``. The TCP covers at
    least ``d_ij = |p_j - p_i|``, so ``T`` is at least the root of ``sum_k L_k D_k(T) = d_ij``
    (increasing in ``T``; found by bisection, the lower end kept). A timed program's leg
    (toppra under the same limits, :func:`weldplan.robot.program.time_route`) is such a motion
    or a chain of them; its detours only lengthen it.
    """
    P = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    L = np.asarray(lever, dtype=np.float64)
    v = np.asarray(velocity, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64)
    d = np.linalg.norm(P[:, None] - P[None], axis=2)
    lo = np.zeros_like(d)
    hi = (d + float(np.sum(L * v * v / a))) / float(np.sum(L * v))  # D_k(T) >= v T - v^2 / a
    for _ in range(TCP_BISECTIONS):
        mid = 0.5 * (lo + hi)
        T = mid[..., None]
        D = np.where(T <= 2 * v / a, a * T * T / 4, v * T - v * v / a)
        reach = (D * L).sum(axis=-1)
        short = reach < d
        lo = np.where(short, mid, lo)
        hi = np.where(short, hi, mid)
    return lo


@dataclass(frozen=True, eq=False)
class PoseFreeLegs:
    """Lower bounds of one robot's timed legs, true whatever gun poses and IK branches its plan
    picks (:func:`pose_free_legs`).

    Attributes
    ----------
    travel
        ``(W, W)`` s: any motion from weld ``i`` to weld ``j``, at rest at both.
    home
        ``(W,)`` s: any motion between the robot's home and weld ``i`` (either way).
    """

    travel: NDArray[np.float64]
    home: NDArray[np.float64]


def _axis_one(robot: Any) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray]:
    """``(o, u, e)``: a point of axis 1, its unit direction and a unit vector across it (part
    frame), so that the azimuth about axis 1 is ``atan2((x - o) . (u x e), (x - o) . e)``."""
    T0 = np.asarray(robot.base) @ np.asarray(robot.origins[0])
    u = T0[:3, :3] @ np.asarray(robot.axes[0], dtype=np.float64)
    u = u / np.linalg.norm(u)
    e = np.eye(3)[int(np.argmin(np.abs(u)))]
    e = e - (e @ u) * u
    return T0[:3, 3], u, e / np.linalg.norm(e)


def _azimuth(
    P: NDArray[np.float64], axis: tuple[NDArray, NDArray, NDArray]
) -> tuple[NDArray, NDArray]:
    """``((n,) rad, (n,) mm)``: the azimuth of points ``P (n, 3)`` about ``axis``
    (:func:`_axis_one`) and their distance from it."""
    o, u, e = axis
    X = np.asarray(P, dtype=np.float64).reshape(-1, 3) - o
    X = X - np.outer(X @ u, u)
    return np.arctan2(X @ np.cross(u, e), X @ e), np.linalg.norm(X, axis=1)


def wrist_centre(robot: Any) -> NDArray[np.float64]:
    """``(3,)`` mm: the wrist centre (where axes 4 and 5 of the URDF chain meet) in the flange
    frame; fixed there for a spherical wrist."""
    q = np.array([0.0, 0.0, 0.0, 0.3, 0.7, 0.0])
    F = robot.link_frames(q)[0]
    pts, dirs = [], []
    for j in (3, 4):
        Tj = F[j] @ robot.origins[j]
        pts.append(Tj[:3, 3])
        dirs.append(Tj[:3, :3] @ robot.axes[j])
    (p1, p2), (d1, d2) = pts, dirs
    # closest points of the two lines: solve [d1 -d2] [s t]^T = p2 - p1 in least squares
    st = np.linalg.lstsq(np.c_[d1, -d2], p2 - p1, rcond=None)[0]
    w = 0.5 * (p1 + st[0] * d1 + p2 + st[1] * d2)
    flange = robot.fk(q)[0]
    return (np.linalg.inv(flange) @ np.r_[w, 1.0])[:3]


def _pi_distance(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """rad: the distance of ``x`` to the nearest multiple of pi (in ``[0, pi / 2]``)."""
    return np.abs(x - np.pi * np.round(x / np.pi))


def axis_one_sets(
    robot: Any, flange_tcp: Any, positions: Any
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """Where axis 1 can be when the TCP is at each weld, whatever the gun pose and branch.

    An OPW arm with no lateral offset (``b = 0``, Brandstötter et al. 2014) keeps its wrist
    centre ``c`` in the plane through axis 1 turned by ``q1``: ``azimuth(c) = q1 + theta0``
    modulo pi (``theta0``: the azimuth at ``q1 = 0``; modulo pi for the arm reaching over its
    back). The wrist centre is fixed in the flange frame and so is the TCP, so ``|p - c| = r``
    (:func:`wrist_centre`, ``flange_tcp``) for every pose: seen from axis 1 the wrist centre is
    within ``h = asin(r / rho)`` of the TCP's azimuth (``rho``: the TCP's distance from the
    axis; ``h = pi / 2`` when ``rho <= r``). So ``q1`` lies within ``h`` of
    ``azimuth(p) - theta0`` modulo pi. A lateral offset ``b`` widens ``h`` by
    ``2 asin(|b| / (rho - r))`` (the offset's angle seen from the axis, either sign).

    Returns
    -------
    centre, half, theta0
        ``(W,)`` rad: ``azimuth(p) - theta0``; ``(W,)`` rad: ``h``; rad: ``theta0``.
    """
    axis = _axis_one(robot)
    F = np.eye(4) if flange_tcp is None else np.asarray(flange_tcp, dtype=np.float64)
    r = float(np.linalg.norm(F[:3, 3] - wrist_centre(robot)))
    q0 = np.zeros(6)
    c0 = robot.fk(q0)[0] @ np.r_[wrist_centre(robot), 1.0]
    theta0 = float(_azimuth(c0[None, :3], axis)[0][0])
    phi, rho = _azimuth(positions, axis)
    half = np.where(rho > r, np.arcsin(np.clip(r / np.maximum(rho, 1e-9), 0.0, 1.0)), np.pi / 2)
    b = abs(float(robot.opw.b))
    if b > 0:
        gap = np.maximum(rho - r, 1e-9)
        half = np.where(gap > b, half + 2 * np.arcsin(np.clip(b / gap, 0.0, 1.0)), np.pi / 2)
    return phi - theta0, np.minimum(half, np.pi / 2), theta0


def pose_free_legs(robot: Any, flange_tcp: Any, positions: Any, home: Any = None) -> PoseFreeLegs:
    """The :class:`PoseFreeLegs` of ``robot`` (placed at its base) with the tool
    ``flange_tcp`` (``(4, 4)`` mm, ``None``: the flange) over the welds ``positions (W, 3)`` mm,
    and its ``home`` (``(6,)`` rad; ``None``: no home term, zeros).

    Each bound is the larger of two, both necessary for any motion at rest at both ends under
    the robot's joint limits (each a lower bound of a chain of such motions too: both times are
    concave in the distance, so pieces never add up to less):

    * the TCP covers the straight distance between the two TCP positions
      (:func:`tcp_leg_bound`; at home, the TCP's position at the home configuration);
    * axis 1 turns at least the angular gap between the sets of :func:`axis_one_sets` (at home:
      from its home angle to weld ``i``'s set), the 1D bang-coast-bang time of that turn
      (:func:`weldplan.robot.route.legtime.rest_to_rest_bound`).
    """
    from weldplan.robot.route.legtime import rest_to_rest_bound

    P = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    F = np.eye(4) if flange_tcp is None else np.asarray(flange_tcp, dtype=np.float64)
    L = lever_arms(robot.opw, float(np.linalg.norm(F[:3, 3])))
    v, a = np.asarray(robot.velocity), np.asarray(robot.acceleration)
    centre, half, theta0 = axis_one_sets(robot, F, P)
    gap = np.maximum(_pi_distance(centre[:, None] - centre[None]) - half[:, None] - half[None], 0)
    travel = np.maximum(tcp_leg_bound(P, L, v, a), rest_to_rest_bound(gap[..., None], v[:1], a[:1]))
    if home is None:
        return PoseFreeLegs(travel, np.zeros(len(P)))
    qh = np.asarray(home, dtype=np.float64).reshape(6)
    h = (robot.fk(qh) @ F)[0, :3, 3]
    tcp = tcp_leg_bound(np.vstack([h, P]), L, v, a)[0, 1:]
    turn = np.maximum(_pi_distance(qh[0] - centre) - half, 0.0)
    return PoseFreeLegs(travel, np.maximum(tcp, rest_to_rest_bound(turn[:, None], v[:1], a[:1])))
