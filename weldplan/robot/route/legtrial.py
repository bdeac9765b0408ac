"""The legs the walk will have to plan, named before it starts: the transfer trial on the
robot's own path at its base (:func:`leg_trial`).

The base search judges its best candidates by the transfers of the point-tip route's order
(:func:`weldplan.robot.placement.join_welds`); it does not run for a base given with
``--robot-base``, and the robot follows the tool stage's order, not the point-tip route's. So
:func:`weldplan.robot.route.assemble` first runs the same trial on the path it is about to walk,
with the walk's own first tries: for every two consecutive served welds whose own leg is blocked,
the ways off both welds (:meth:`~weldplan.robot.route.Detour.leave`: the gun's proven exits, else
a retract) joined by a straight or tucked-arm joint motion
(:meth:`~weldplan.robot.route.Detour.joins_directly`), else another pair of their ways off
(:meth:`~weldplan.robot.route.Detour.ways_off`; the walk's ``pair``, whose answers it reuses).
No planner runs: the trial costs a few FCL checks a leg and gives the same answer on any machine.
Each leg it leaves *split* is named at once with its cause (a warning: the run says within
seconds which legs are in doubt, whatever the OMPL runs after it take), and the walk shares its
route-wide OMPL retry budget among those legs and the ones it cannot foresee
(:meth:`LegTrial.retry_share`). Measured on car2_200 at the seed-0 base turned -30 deg: its one
split leg (Z4L-134 -> Z4L-3) given the route's whole 8,000 retry checks stayed unsolved, and the
welds after it, each a fresh target into the same pocket, then got no retry: so one split leg
keeps one leg's cap.

Issue 27, targets 1-2 ("says within 60 s which welds cannot be joined and why").
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

log = logging.getLogger(__name__)

#: split legs a warning names (all of them are in :attr:`LegTrial.split`)
SPLITS_NAMED = 12


@dataclass(frozen=True)
class LegTrial:
    """What :func:`leg_trial` found on the legs between consecutive served welds.

    Attributes
    ----------
    legs
        Legs between consecutive served welds.
    blocked
        Those whose own joint motion is blocked (each needs a detour).
    split
        Per blocked leg no straight or tucked transfer joins: ``(a, b, why)``, ``a`` and ``b``
        positions in route order of the welds, ``why`` the cause in words (no way off ``a``,
        no way into ``b``, or no straight or tucked transfer between them).
    """

    legs: int
    blocked: int
    split: tuple[tuple[int, int, str], ...]

    def names(self, ids: tuple[str, ...]) -> tuple[str, ...]:
        """``"A -> B: why"`` per split leg (``ids`` the welds' names in route order)."""
        return tuple(f"{ids[a]} -> {ids[b]}: {why}" for a, b, why in self.split)

    def describe(self, ids: tuple[str, ...], at_most: int = SPLITS_NAMED) -> str:
        """One line: the legs, those blocked, those split, the first ``at_most`` named."""
        line = (
            f"{len(self.split)} of {self.legs} leg(s) split ({self.blocked} blocked, "
            f"{self.blocked - len(self.split)} joined by a gun exit or retract and a straight or "
            "tucked transfer)"
        )
        if self.split:
            shown = self.names(ids)[:at_most]
            more = len(self.split) - len(shown)
            line += ": " + "; ".join(shown) + (f"; and {more} more" if more else "")
        return line

    def retry_share(self, total: int, floor: int) -> int:
        """Checks of the route's OMPL retry budget ``total`` that one leg may take: an even
        share among the split legs and one more (the legs the trial cannot foresee: those
        after a weld is dropped, the ways back along the path), at least ``floor`` (the fixed
        per-leg cap) and at most ``total`` (module docstring). A route with no split leg, whose
        walk needs no planner unless a weld is dropped, lets one leg take it all."""
        return int(min(total, max(floor, total // (len(self.split) + 1))))


def leg_hits(
    det: Any, q: NDArray, own: NDArray, ia: int, ib: int, blocked: set[int] | None
) -> list[Any]:
    """The first blocked motion of the route's own rows ``ia..ib`` (``[]``: free), from the
    caller's ``blocked`` motions when given, else checked here (``own[i]``: the contact zone is
    exempt on the motion leaving row ``i``)."""
    if blocked is None:
        return det.checker.path_hits(q[ia : ib + 1], own[ia:ib], first_only=True)
    at = sorted(s for s in blocked if ia <= s < ib)
    if not at:
        return []
    return det.checker.path_hits(q[at[0] : at[0] + 2], own[at[0] : at[0] + 1])


def leg_trial(
    det: Any,
    q: NDArray[np.float64],
    rows: NDArray[np.int64],
    served: list[int],
    own: NDArray[np.bool_],
    blocked: set[int] | None,
    pair: Callable[[int, int], tuple[Any, Any, Any]],
) -> LegTrial:
    """The transfer trial over the consecutive ``served`` welds (positions in route order, at
    route rows ``rows``) of the joint path ``q (m, 6)`` rad (module docstring).

    Parameters
    ----------
    det
        The walk's :class:`~weldplan.robot.route.Detour`.
    own, blocked
        As :func:`leg_hits`: the route's own motions with the contact zone exempt, and those the
        caller's check found blocked (``None``: checked here).
    pair
        ``pair(route row a, route row b) -> (way off a, way into b, transfer)``: the walk's own
        join without a planner (cached), each ``(p, 6)`` rad or ``None`` (no way off that weld;
        no straight or tucked transfer between any of their ways).
    """
    n_blocked, split = 0, []
    for a, b in zip(served[:-1], served[1:], strict=True):
        ia, ib = int(rows[a]), int(rows[b])
        hits = leg_hits(det, q, own, ia, ib, blocked)
        if not hits:
            continue
        n_blocked += 1
        la, lb, mid = pair(ia, ib)
        if la is None or lb is None:
            end = "start" if la is None else "end"
            split.append((a, b, f"{hits[0].body} on its own motion, no gun exit or retract at its "
                                f"{end}"))  # fmt: skip
        elif mid is None:
            split.append((a, b, f"{hits[0].body} on its own motion, no straight or tucked "
                                "transfer"))  # fmt: skip
    return LegTrial(max(len(served) - 1, 0), n_blocked, tuple(split))
