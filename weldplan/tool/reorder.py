"""The weld order and the gun's transitions together: a blocked transition re-orders the welds.

:func:`~weldplan.tool.tool_order.tool_order` prices each pair of welds by an estimate of its
transition; only :func:`~weldplan.tool.transitions.plan_transitions` finds out whether the swept
tool can actually pass. A pair whose transition is blocked (every exit tried, and SE(3) where
allowed) is priced out of the next order (``forbid``) and the transitions are planned again, up
to ``rounds`` orders or until no new pair is blocked. The path with the fewest blocked
transitions (then the shortest) is kept; every transition of it is planned and checked as
always, and the caller re-checks the path independently
(:func:`~weldplan.tool.verify_sweeps.verify_sweeps`).
"""

from __future__ import annotations

import logging
from typing import Any

from weldplan.tool.result import WeldPoses
from weldplan.tool.tool_order import tool_order
from weldplan.tool.transit import ToolPath
from weldplan.tool.transitions import plan_transitions

log = logging.getLogger(__name__)

#: orders tried when transitions are found blocked
REORDER_ROUNDS = 3


def plan_ordered_transitions(
    part: Any,
    tool: Any,
    poses: WeldPoses,
    *,
    retract: float,
    rot_weight: float,
    seed: Any = None,
    price_lifts: bool = True,
    keep_order: bool = False,
    rounds: int = REORDER_ROUNDS,
    reuse: Any = None,
    **settings: Any,
) -> ToolPath:
    """Order the welds on the tool's costs and plan the transitions, re-ordering round blocked
    pairs (module docstring).

    Parameters
    ----------
    part, tool, poses
        As :func:`~weldplan.tool.transitions.plan_transitions`.
    retract, rot_weight
        The order's leg costs (:func:`~weldplan.tool.tool_order.tool_order`; ``retract`` also
        goes to the transitions).
    price_lifts
        With ``reuse`` (the exit test's planner): a weld that planner leaves by a lift is priced
        at the lift, not the axial retract (:func:`weldplan.tool.exits.leave_distances`).
    seed
        The sequencer's and OMPL's seed.
    keep_order
        Keep the poses' own order (the point-tip route's) and never re-order.
    rounds
        At most this many orders.
    reuse, settings
        Passed on to :func:`~weldplan.tool.transitions.plan_transitions` (the exit test's
        planner; ``se3``, ``time_s``, ``side_exit``, ``slide``, ``workers``...).

    Returns
    -------
    ToolPath
        Its ``stats`` carry the order's estimated costs, ``order_rounds`` and
        ``forbidden_pairs`` (the pairs priced out when the kept order was made).
    """
    leave = None
    if reuse is not None and price_lifts:
        from weldplan.tool.exits import leave_distances

        leave = leave_distances(reuse, poses)
    forbid: set[tuple[str, str]] = set()
    best: ToolPath | None = None
    for k in range(1, max(int(rounds), 1) + 1):
        order, stats = tool_order(poses, retract, rot_weight, rng=seed, leave=leave, forbid=forbid)
        if keep_order:
            order = [p.id for p in poses.poses if p.ok]
        stats["order_from"] = "route" if keep_order else "tool"
        stats["order_rounds"] = k
        path = plan_transitions(
            part, tool, poses, order=order, retract=retract, rot_weight=max(rot_weight, 1.0),
            seed=seed, stats=stats, reuse=reuse, **settings,
        )  # fmt: skip
        if best is None or (len(path.blocked), path.length) < (len(best.blocked), best.length):
            best = path
        new = {(t.from_id, t.to_id) for t in path.blocked} - forbid
        if not new or keep_order:
            break
        log.info("tool order: %d transition(s) blocked; re-ordering round them", len(new))
        forbid |= new
    assert best is not None
    return best
