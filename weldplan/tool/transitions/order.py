"""The weld order on the tool's own costs (issue 16, item 4), not on point-tip lengths.

The tool leaves weld ``i`` by retracting ``retract`` mm along its TCP axis to the retract point
``r_i = p_i - retract z_i``, moves to ``r_j`` while its orientation turns from ``q_i`` to
``q_j`` (slerp), and approaches weld ``j`` along its axis (:mod:`weldplan.tool.transitions.plan`).
The estimated cost of that transition is its TCP length plus a weight on its rotation::

    c_ij = 2 retract + |r_i - r_j| + w angle(q_i, q_j)          (mm; w in mm per rad)

the length and rotation of the direct transition. A weld left by a lift instead (a C-gun whose
exit is a slide along the flange, ``leave``: :func:`weldplan.tool.poses.leave_distances`) has
its own distance ``d_i`` in place of ``retract``: ``c_ij = d_i + d_j + |r_i - r_j| + w angle``
with ``r_i = p_i - d_i z_i``. It is a lower bound-like estimate: a
transition re-planned in SE(3) is longer. The order is the open path of least total cost over
the welds with a pose (:func:`weldplan.optim.discrete.sequence.solve_sequence`: exact up to its
exact limit, above it nearest neighbour + the seeded polish: the same seed, the same order).
The poses are those chosen along the point-tip order
(:func:`weldplan.tool.poses.plan_weld_poses`); they are not re-chosen for the new order.

Pairs whose transition was found blocked (``forbid``: the transition planner tried every exit
and, where allowed, SE(3)) are avoided in both directions wherever an order can do without them
(unreachable for the exact solver, penalised above every order without them above its size);
:mod:`weldplan.tool.transitions.reorder` re-orders until no new pair is blocked.
"""

from __future__ import annotations

import logging
from collections.abc import Collection, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.tool.poses.result import WeldPoses
from weldplan.tool.settings import DEFAULT_ROT_WEIGHT
from weldplan.tool.transitions.sweep import quat_to_matrix

log = logging.getLogger(__name__)


def retract_points(
    poses: WeldPoses, ids: list[str], retract: float | NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(n, 3)`` mm: each weld's retract point ``p - retract z`` (z the TCP axis of its pose;
    ``retract`` mm, one for all or ``(n,)``)."""
    P = np.array([poses[i].position for i in ids], dtype=np.float64)
    Q = np.array([poses[i].quaternion for i in ids], dtype=np.float64)
    d = np.broadcast_to(np.asarray(retract, dtype=np.float64), (len(ids),))
    return P - d[:, None] * quat_to_matrix(Q)[:, :, 2]


def tool_leg_costs(
    poses: WeldPoses,
    ids: list[str],
    retract: float,
    rot_weight: float,
    leave: Mapping[str, float] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The estimated tool costs between the welds ``ids`` (all with a pose), module docstring;
    ``leave``: weld id -> mm it is left by along its axis when not ``retract`` (a lift).

    Returns
    -------
    cost, length, angle
        ``(n, n)`` mm, ``(n, n)`` mm of TCP path, ``(n, n)`` rad of rotation.
    """
    d = np.array([(leave or {}).get(i, retract) for i in ids], dtype=np.float64)
    R = retract_points(poses, ids, d)
    Q = np.array([poses[i].quaternion for i in ids], dtype=np.float64)
    length = np.linalg.norm(R[:, None, :] - R[None, :, :], axis=2) + d[:, None] + d[None, :]
    angle = 2.0 * np.arccos(np.clip(np.abs(Q @ Q.T), 0.0, 1.0))
    np.fill_diagonal(length, 0.0)
    np.fill_diagonal(angle, 0.0)
    return length + rot_weight * angle, length, angle


def order_cost(cost: NDArray[np.float64], order: list[int]) -> float:
    """The summed cost of consecutive pairs along ``order``."""
    return float(sum(cost[a, b] for a, b in zip(order[:-1], order[1:], strict=True)))


def _avoiding_order(cost: NDArray[np.float64], avoid: NDArray[np.bool_], rng: Any) -> list[int]:
    """The least-cost open path that uses ``avoid`` pairs only where no order does without them:
    exactly (those pairs unreachable; if no order is left, as if none were avoided) up to the
    exact solver's size, else the sequencer's penalty of ``avoid`` above any order over the other
    pairs."""
    from weldplan.errors import PlanningError
    from weldplan.optim.discrete.sequence import EXACT_MAX_NODES, solve_sequence

    if not avoid.any():
        return [int(k) for k in solve_sequence(cost, rng=rng).order]
    if len(cost) <= EXACT_MAX_NODES:
        try:
            return [int(k) for k in solve_sequence(np.where(avoid, np.inf, cost), rng=rng).order]
        except PlanningError:
            return [int(k) for k in solve_sequence(cost, rng=rng).order]
    return [int(k) for k in solve_sequence(cost, rng=rng, avoid=avoid).order]


def tool_order(
    poses: WeldPoses,
    retract: float,
    rot_weight: float = DEFAULT_ROT_WEIGHT,
    *,
    rng: Any = None,
    leave: Mapping[str, float] | None = None,
    forbid: Collection[tuple[str, str]] = (),
) -> tuple[list[str], dict[str, Any]]:
    """The order of the welds with a pose that minimises the tool costs (module docstring).

    Parameters
    ----------
    poses
        The weld poses, in the point-tip route's order.
    retract
        mm along the TCP axis.
    rot_weight
        mm per rad.
    rng
        Seed for the sequencer (used above its exact limit).
    leave
        Weld id -> mm it is left by along its axis where that is not ``retract`` (a lift:
        :func:`weldplan.tool.poses.leave_distances`).
    forbid
        ``(from_id, to_id)`` pairs whose transition was found blocked: used (either way) only
        where no order does without them.

    Returns
    -------
    order, stats
        The weld ids in the new order, and the estimated costs (mm, mm, deg) of the point-tip
        order and of the new one.
    """
    ids = [p.id for p in poses.poses if p.ok]
    stats: dict[str, Any] = {"rot_weight": rot_weight}
    if len(ids) < 3:
        return ids, stats
    cost, length, angle = tool_leg_costs(poses, ids, retract, rot_weight, leave)
    stats["lifted"] = sum(i in (leave or {}) for i in ids)
    avoid = np.zeros(cost.shape, dtype=bool)
    where = {w: k for k, w in enumerate(ids)}
    for a, b in forbid:
        if a in where and b in where:
            avoid[where[a], where[b]] = avoid[where[b], where[a]] = True
    stats["forbidden_pairs"] = len(forbid)
    point = list(range(len(ids)))
    order = _avoiding_order(cost, avoid, rng)

    def key(o: list[int]) -> tuple[int, float]:  # pairs priced out first, then the cost
        return sum(avoid[a, b] for a, b in zip(o[:-1], o[1:], strict=True)), order_cost(cost, o)

    if key(order) > key(point):  # never worse than the point-tip order
        order = point
    stats["forbidden_used"] = key(order)[0]
    for name, o in (("point_order", point), ("tool_order", order)):
        stats[name] = {
            "cost": order_cost(cost, o),
            "length": order_cost(length, o),
            "rotation_deg": float(np.degrees(order_cost(angle, o))),
        }
    log.info(
        "tool order: estimated cost %.1f mm (point-tip order %.1f mm)",
        stats["tool_order"]["cost"],
        stats["point_order"]["cost"],
    )
    return [ids[k] for k in order], stats
