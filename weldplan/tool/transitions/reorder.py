"""The weld order and the gun's transitions together: a blocked transition re-orders the welds.

:func:`~weldplan.tool.transitions.tool_order` prices each pair of welds by an estimate of its
transition; only :func:`~weldplan.tool.transitions.plan_transitions` finds out whether the swept
tool can actually pass. A pair whose transition is blocked (every exit tried, and SE(3) where
allowed) is priced out of the next order (``forbid``) and the transitions are planned again, up
to ``rounds`` orders or until no new pair is blocked. The path with the fewest blocked
transitions (then the shortest) is kept; every transition of it is planned and checked as
always, and the caller re-checks the path independently
(:func:`~weldplan.tool.verify.verify_sweeps`).
"""

from __future__ import annotations

import logging
from typing import Any

from weldplan.tool.poses.result import WeldPoses
from weldplan.tool.settings import OrderSettings, TransitionSettings
from weldplan.tool.transitions.order import tool_order
from weldplan.tool.transitions.plan import TransitionPlanner, plan_transitions
from weldplan.tool.transitions.result import ToolPath

log = logging.getLogger(__name__)


def plan_ordered_transitions(
    part: Any,
    tool: Any,
    poses: WeldPoses,
    settings: TransitionSettings | None = None,
    order: OrderSettings | None = None,
    *,
    reuse: TransitionPlanner | None = None,
) -> ToolPath:
    """Order the welds on the tool's costs and plan the transitions, re-ordering round blocked
    pairs (module docstring).

    Parameters
    ----------
    part, tool, poses
        As :func:`~weldplan.tool.transitions.plan_transitions`.
    settings
        The transitions' (:class:`~weldplan.tool.settings.TransitionSettings`; default those of
        ``reuse``, else the defaults); its ``retract`` and ``seed`` are the order's too (the
        leg costs, the sequencer's seed).
    order
        The order's leg cost weight, whether to keep the poses' order, the lifts' prices and
        the rounds (:class:`~weldplan.tool.settings.OrderSettings`; default its defaults).
    reuse
        The exit test's planner, passed on to
        :func:`~weldplan.tool.transitions.plan_transitions` (its checked exits are reused).

    Returns
    -------
    ToolPath
        Its ``stats`` carry the order's estimated costs, ``order_rounds`` and
        ``forbidden_pairs`` (the pairs priced out when the kept order was made).
    """
    o = order if order is not None else OrderSettings()
    s = settings if settings is not None else (
        reuse.settings if reuse is not None else TransitionSettings())  # fmt: skip
    leave = None
    if reuse is not None and o.price_lifts:
        from weldplan.tool.poses.exits import leave_distances

        leave = leave_distances(reuse, poses)
    forbid: set[tuple[str, str]] = set()
    best: ToolPath | None = None
    for k in range(1, o.rounds + 1):
        ids, stats = tool_order(poses, s.retract, o.rot_weight, rng=s.seed, leave=leave,
                                forbid=forbid)  # fmt: skip
        if o.keep_order:
            ids = [p.id for p in poses.poses if p.ok]
        stats["order_from"] = "route" if o.keep_order else "tool"
        stats["order_rounds"] = k
        path = plan_transitions(part, tool, poses, s, order=ids, stats=stats, reuse=reuse)
        if best is None or (len(path.blocked), path.length) < (len(best.blocked), best.length):
            best = path
        new = {(t.from_id, t.to_id) for t in path.blocked} - forbid
        if not new or o.keep_order:
            break
        log.info("tool order: %d transition(s) blocked; re-ordering round them", len(new))
        forbid |= new
    assert best is not None
    return best
