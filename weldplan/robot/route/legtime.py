"""Leg times between welds for ``--cost time``: configurations per weld, a proved lower bound.

The sequencer orders welds by a cost matrix. With ``--cost time`` that cost is the robot's time
for each leg, known before any order exists only through the configurations the robot can take
at the two welds:

1. :func:`weld_configurations`: every usable IK solution (:func:`weldplan.robot.placement.usable`:
   inside the limits, away from the wrist singularity) of the flange pose at each weld, with its
   full-turn equivalents (:func:`weldplan.robot.route.turn_variants`);
2. :func:`rest_to_rest_bound`: the least time any motion needs between two configurations when
   it starts and ends at rest (the robot welds at both ends): each joint ``j`` must travel at
   least ``d_j = |q_b,j - q_a,j|`` under ``|q'_j| <= v_j`` and ``|q''_j| <= a_j``, which takes at
   least the 1D bang-coast-bang time ``d / v + v / a`` (``2 sqrt(d / a)`` when ``d < v^2 / a``),
   so the leg takes at least the largest of them. Vias, detours and stops on the way only add
   time: this bounds the timed result (:func:`weldplan.robot.program.time_route`) of any joint
   path between those configurations, whatever the route between the welds looks like;
3. :func:`leg_times`: two ``(n, n)`` matrices in seconds.

   * ``bound``: the least of (2) over every pair of usable configurations of the two welds: a
     lower bound of the leg whatever configurations the robot route picks later (the branch
     choice, :mod:`weldplan.robot.route.configs`, runs after the order is known). The optimum of an
     open path over it, plus the weld time of every weld, is a *proved* lower bound of the cycle
     time of any order (``Route.stats["time_bound"]``).
   * ``cost`` (what the sequencer minimises): the least of (2) over pairs on the *station
     branch* (the branch usable at most welds: the robot route avoids branch changes, 1000 s
     each). Where a weld has no solution on that branch it falls back to the ``bound`` entry.
     It is itself a lower bound of a leg the robot route takes on that branch, and never below
     ``bound``.

A weld with no usable configuration (the robot cannot serve it; the robot route passes it in
joint space without welding) costs 0 s to and from it: the only bound that holds for a joint
vector the route has not chosen yet. Named deviation from the issue's "timed result itself for
planned legs": legs are costed by (2) only, never by timing a planned joint path, so the costs
stay lower bounds and one cost matrix serves every round of the lazy planning.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class WeldConfigurations:
    """The usable configurations of ``n`` welds (:func:`weld_configurations`).

    Attributes
    ----------
    q
        ``(n, K, 6)`` rad: every usable IK solution with its full-turn equivalents.
    branch
        ``(n, K) int``: the IK branch of each (:mod:`weldplan.robot.model.ik`'s bits).
    valid
        ``(n, K) bool``: a usable solution (inside the limits, not near-singular).
    """

    q: NDArray[np.float64]
    branch: NDArray[np.int64]
    valid: NDArray[np.bool_]

    @property
    def served(self) -> NDArray[np.bool_]:
        """``(n,) bool``: the weld has a usable configuration."""
        return self.valid.any(axis=1)

    def station_branch(self) -> int:
        """The branch usable at most welds (lowest label on ties), -1 when none is usable."""
        counts = np.array([(self.valid & (self.branch == b)).any(axis=1).sum() for b in range(8)])
        return int(np.argmax(counts)) if counts.max() > 0 else -1


@dataclass(frozen=True, eq=False)
class LegTimes:
    """Leg times between welds, seconds (module docstring).

    Attributes
    ----------
    cost
        ``(n, n)`` s: what the sequencer minimises (station branch).
    bound
        ``(n, n)`` s: a lower bound of the leg for any configurations (``bound <= cost``).
    weld_time
        s a weld spot (the dwell added once per served weld).
    served
        ``(n,) bool``: welds with a usable configuration.
    branch
        The station branch ``cost`` is taken on (-1: none).
    """

    cost: NDArray[np.float64]
    bound: NDArray[np.float64]
    weld_time: float
    served: NDArray[np.bool_]
    branch: int

    def order_time(self, order: ArrayLike, *, bound: bool = False) -> float:
        """s: the legs of the open ``order`` (joint indices) over ``cost`` (or ``bound``) plus
        the dwell of every served weld."""
        o = np.asarray(order, dtype=np.intp)
        M = self.bound if bound else self.cost
        return float(M[o[:-1], o[1:]].sum() + self.weld_time * self.served[o].sum())


def rest_to_rest_bound(
    dq: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike
) -> NDArray[np.float64]:
    """``(...)`` s: the least time of any rest-to-rest motion with joint displacements
    ``dq (..., d)`` rad under ``|q'_j| <= v_j`` rad/s and ``|q''_j| <= a_j`` rad/s^2 (module
    docstring, step 2): ``max_j`` of the 1D time-optimal (bang-coast-bang) time of joint ``j``.

    Never above :func:`weldplan.robot.program.pair_time` (the straight joint move that keeps the
    joints synchronised), equal to it for a single-joint move.
    """
    v = np.asarray(velocity, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64)
    if v.shape != a.shape or not (np.all(v > 0) and np.all(a > 0)):
        raise ConfigError("velocity and acceleration limits must be > 0", field="limits")
    d = np.abs(np.asarray(dq, dtype=np.float64))
    coast = d / v + v / a
    tri = 2.0 * np.sqrt(d / a)
    return np.where(d * a >= v * v, coast, tri).max(axis=-1)


def weld_configurations(
    robot: object, T_flange: ArrayLike, *, singular_deg: float | None = None
) -> WeldConfigurations:
    """Every usable configuration of the flange poses ``T_flange (n, 4, 4)`` mm (part frame;
    NaN poses: a weld without a tool pose, no configuration).

    ``robot`` is a placed :class:`~weldplan.robot.model.Robot`; ``singular_deg`` defaults to
    :data:`weldplan.robot.placement.DEFAULT_SINGULAR_DEG`, the robot route's own threshold.
    """
    from weldplan.robot.placement.reach import DEFAULT_SINGULAR_DEG, usable
    from weldplan.robot.route.configs import turn_variants

    sd = DEFAULT_SINGULAR_DEG if singular_deg is None else float(singular_deg)
    T = np.asarray(T_flange, dtype=np.float64).reshape(-1, 4, 4)
    has = np.all(np.isfinite(T), axis=(1, 2))
    br = robot.ik_all(np.where(has[:, None, None], T, np.eye(4)))  # type: ignore[attr-defined]
    ok = usable(br, sd) & has[:, None]
    Q, branch, valid = turn_variants(br, robot.lower, robot.upper, ok)  # type: ignore[attr-defined]
    return WeldConfigurations(Q, branch, valid)


#: configurations compared per chunk in :func:`_min_matrix` (bounds its memory)
CHUNK_ELEMENTS = 2_000_000


def _min_matrix(
    Q: NDArray, valid: NDArray[np.bool_], v: NDArray, a: NDArray
) -> NDArray[np.float64]:
    """``(n, n)`` s: for every pair of welds the least :func:`rest_to_rest_bound` over their
    valid configurations ``Q (n, K, 6)`` / ``valid (n, K)``; ``inf`` where either has none."""
    n = len(valid)
    K = int(valid.sum(axis=1).max()) if n else 0
    # each weld's valid configurations first, padded to the most any weld has
    col = np.argsort(~valid, axis=1, kind="stable")[:, :K]
    Q = np.take_along_axis(Q, col[:, :, None], axis=1)
    valid = np.take_along_axis(valid, col, axis=1)
    out = np.full((n, n), np.inf)
    if K == 0:
        return out
    step = max(1, CHUNK_ELEMENTS // max(1, K * K * 6))
    for i in range(n):
        Qi = Q[i, valid[i]]  # (ki, 6)
        if not len(Qi):
            continue
        for j0 in range(0, n, step):
            Qj = Q[j0 : j0 + step]  # (c, K, 6)
            t = rest_to_rest_bound(Qj[:, None] - Qi[None, :, None], v, a)  # (c, ki, K)
            t = np.where(valid[j0 : j0 + step, None, :], t, np.inf)
            out[i, j0 : j0 + step] = t.min(axis=(1, 2))
    np.fill_diagonal(out, 0.0)
    return out


def leg_times(
    configs: WeldConfigurations,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    *,
    weld_time: float = 0.0,
) -> LegTimes:
    """The ``cost`` and ``bound`` matrices of the module docstring (seconds).

    Parameters
    ----------
    configs
        From :func:`weld_configurations`, ``n`` welds.
    velocity, acceleration
        ``(6,)`` rad/s and rad/s^2: the limits the cycle is timed with (scaled as the run asks).
    weld_time
        s a spot.
    """
    from weldplan.robot.program.timing import check_weld_time

    wt = check_weld_time(weld_time)
    v = np.asarray(velocity, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64)
    b0 = configs.station_branch()
    bound = _min_matrix(configs.q, configs.valid, v, a)
    bound[~np.isfinite(bound)] = 0.0  # a weld without configuration: 0 s is all that holds
    on = configs.valid & (configs.branch == b0)
    cost = _min_matrix(configs.q, on, v, a)
    cost = np.where(np.isfinite(cost), cost, bound)
    n = len(configs.q)
    served = configs.served
    log.info(
        "leg times: %d welds, %d served, station branch %d, mean leg bound %.3f s",
        n,
        int(served.sum()),
        b0,
        float(bound[np.triu_indices(n, 1)].mean()) if n > 1 else 0.0,
    )
    return LegTimes(cost, bound, wt, served, b0)


def weld_flange_poses(poses: Any, joint_ids: tuple[str, ...], flange_tcp: ArrayLike) -> NDArray:
    """``(n, 4, 4)`` mm: the flange pose at each weld ``joint_ids`` of the
    :class:`~weldplan.tool.poses.WeldPoses` ``poses``; NaN where the weld has no free pose."""
    inv = np.linalg.inv(np.asarray(flange_tcp, dtype=np.float64).reshape(4, 4))
    T = np.full((len(joint_ids), 4, 4), np.nan)
    for k, jid in enumerate(joint_ids):
        p = poses[str(jid)]
        if p.ok:
            Tk = np.eye(4)
            Tk[:3, :3] = p.rotation()
            Tk[:3, 3] = p.position
            T[k] = Tk @ inv
    return T


def cell_leg_times(
    cell: Any,
    tool: Any,
    robot: Any,
    flange_tcp: ArrayLike,
    *,
    weld_time: float = 0.0,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    search: Any = None,
    **pose_options: Any,
) -> tuple[LegTimes, Any]:
    """Leg times between every pair of the cell's welds, before any order exists.

    The weld poses are planned once per weld (:func:`weldplan.tool.plan_weld_poses` over the
    cell's joints; a weld's pose does not depend on the order, ``pose_options`` are its
    options); the robot stays at its base, or, with ``search``
    (:class:`~weldplan.robot.placement.BaseSearch`), is placed at the best base for those poses
    (:func:`weldplan.robot.placement.search_base`).

    Returns
    -------
    (LegTimes, Robot)
        Over ``cell.joints.ids`` in file order; the robot as placed (keep it for the robot
        route, so the times are of the same base).

    Raises
    ------
    PlanningError
        No weld has a free tool pose, or the robot serves none of them.
    """
    from weldplan.robot.placement.reach import search_base
    from weldplan.tool import plan_weld_poses
    from weldplan.tool.settings import PoseSearchSettings

    poses = plan_weld_poses(cell, None, tool, PoseSearchSettings(**pose_options))
    T = weld_flange_poses(poses, tuple(str(i) for i in cell.joints.ids), flange_tcp)
    has = np.all(np.isfinite(T), axis=(1, 2))
    if not has.any():
        raise PlanningError("--cost time: no weld has a collision-free tool pose")
    if search is not None:
        best = search_base(robot, T[has], cell.part, search)[0]
        robot = robot.with_base(best.base)  # type: ignore[attr-defined]
        log.info("leg times: base searched from the weld poses: %s", best.xyz_yaw())
    configs = weld_configurations(robot, T)
    if not configs.served.any():
        raise PlanningError("--cost time: the robot serves none of the welds from its base")
    legs = leg_times(
        configs,
        np.asarray(robot.velocity) * velocity_scale,  # type: ignore[attr-defined]
        np.asarray(robot.acceleration) * acceleration_scale,  # type: ignore[attr-defined]
        weld_time=weld_time,
    )
    return legs, robot


#: Held-Karp for the time bound up to this many welds, else the 1-tree bound (as the pipeline's
#: length bounds, :data:`weldplan.weld.pipeline.LOWER_BOUND_EXACT_MAX`)
BOUND_EXACT_MAX = 16
#: CPU-time cap (s) of the 1-tree bound's subgradient ascent
BOUND_SECONDS = 10.0


def time_stats(
    legs: LegTimes, joint_ids: tuple[str, ...], order: tuple[str, ...]
) -> dict[str, object]:
    """What ``Route.stats`` says of an order sequenced with ``--cost time`` (seconds).

    Parameters
    ----------
    legs
        Over the cell's joints ``joint_ids``.
    order
        The route's visiting order (ids; a subset when joints were skipped).

    Returns
    -------
    dict
        ``time_cost`` (the order over ``legs.cost`` plus the dwell: what the sequencer
        minimised), ``time_bound`` (the open-path optimum over ``legs.bound`` over the visited
        welds, plus the same dwell: a proved lower bound of the timed cycle of *any* order and
        configurations, the timed result of the robot stage included), ``time_bound_method``
        (``"held-karp"``, ``"1-tree"`` or ``"trivial"``), ``time_gap`` (``time_cost / time_bound
        - 1``), ``time_bound_order`` (the order over ``legs.bound``), ``station_branch``,
        ``weld_time``.
    """
    from weldplan.optim.discrete.sequence import solve_sequence

    pos = {str(j): k for k, j in enumerate(joint_ids)}
    o = np.array([pos[str(j)] for j in order], dtype=np.intp)
    cost = legs.order_time(o)
    dwell = legs.weld_time * float(legs.served[o].sum())
    B = legs.bound[np.ix_(o, o)]
    m = len(o)
    if m < 2:
        lb, method = 0.0, "trivial"
    elif m <= BOUND_EXACT_MAX:
        lb, method = float(solve_sequence(B, method="exact").cost), "held-karp"
    else:
        from weldplan.optim.discrete.bounds import one_tree_bound

        lb = float(one_tree_bound(B, open_path=True, upper=cost, max_seconds=BOUND_SECONDS))
        method = "1-tree"
    bound = lb + dwell
    return {
        "cost": "time",
        "time_cost": cost,
        "time_bound": bound,
        "time_bound_method": method,
        "time_gap": cost / bound - 1.0 if bound > 0 else float("nan"),
        "station_branch": legs.branch,
        "weld_time": legs.weld_time,
    }
