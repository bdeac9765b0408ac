"""Lazy costs that converge: re-sequence over lower bounds until the route is close to them.

The lazy pipeline (:mod:`weldplan.weld.pipeline`) orders the joints over *known* legs first (an
unknown leg is avoided where the known ones connect), so the route uses only planned legs. That
route can sit well above the best route through the station: legs never planned keep their
straight-polyline estimates, which are lower bounds, and some of those legs may be far better
than the known detours (issue #18: 5.5 % at 1000 joints, most of it from this).

:func:`close_gap` closes it the way lazy shortest-path and row-generation schemes do:

1. order the joints *optimistically*, over the matrix ``C`` in which every leg costs what is
   proved of it (a planned leg its path length, any other its straight-polyline lower bound);
2. if that order uses only known legs, it is a route, and (up to the sequencer's own gap) the best
   one: stop (``"optimistic order is known"``);
3. else compare the route with the optimistic order's cost: under ``target`` (relative) stop
   (``"within target of the optimistic order"``); otherwise plan the unknown legs the optimistic
   order uses (and their ends' nearest unknown pairs), re-sequence known-first, repeat.

Every planned leg raises ``C`` towards the true costs, so the optimistic order rises towards the
route; each round plans at least one new pair, so the loop ends. The caller then states the gap
against a *proved* bound (Held-Karp or the 1-tree bound over the same ``C``, never over
estimates that are not lower bounds): the optimistic order's cost is a heuristic value, used
here only to decide when to stop.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

log = logging.getLogger(__name__)

#: default relative gap between the route and the optimistic order at which the rounds stop
#: (the 1-tree bound reported in the end sits another ~1 % below the optimistic order)
GAP_TARGET = 0.01
#: default bound on the gap-closing rounds
GAP_ROUNDS = 30


@dataclass(frozen=True)
class GapRounds:
    """What :func:`close_gap` did.

    Attributes
    ----------
    rounds
        Optimistic orders computed.
    pairs_planned
        Legs planned by these rounds.
    optimistic_cost
        mm: cost of the last optimistic order over ``C`` (a heuristic value, not a bound).
    reason
        Why it stopped.
    history
        ``(route cost, optimistic cost)`` per round, mm.
    """

    rounds: int
    pairs_planned: int
    optimistic_cost: float
    reason: str
    history: tuple[tuple[float, float], ...]

    def to_dict(self) -> dict[str, Any]:
        return {
            "rounds": self.rounds,
            "pairs_planned": self.pairs_planned,
            "optimistic_cost": self.optimistic_cost,
            "reason": self.reason,
            "history": [list(h) for h in self.history],
        }


def order_pairs(order: Any, pair_index: NDArray[np.intp]) -> NDArray[np.intp]:
    """Pair indices of the legs of an open ``order``."""
    o = np.asarray(order, dtype=np.intp)
    return pair_index[o[:-1], o[1:]]


def close_gap(
    seq: Any,
    C: NDArray[np.float64],
    known: NDArray[np.bool_],
    pair_index: NDArray[np.intp],
    *,
    optimistic: Callable[[NDArray[np.float64]], Any],
    plan: Callable[[list[int]], None],
    resequence: Callable[[], Any],
    near: Callable[[list[int]], list[int]],
    target: float = GAP_TARGET,
    max_rounds: int = GAP_ROUNDS,
) -> tuple[Any, GapRounds]:
    """Plan the legs that optimistic orders use until the route is within ``target`` of one.

    Parameters
    ----------
    seq
        The current route's :class:`~weldplan.optim.discrete.sequence.Sequence` (known legs only).
    C
        ``(n, n) float`` mm: known legs at their planned length (``inf`` when planning failed),
        unknown legs at their lower-bound estimate. Updated in place by ``plan``.
    known
        ``(n_pairs,) bool``, updated in place by ``plan``.
    pair_index
        ``(n, n) int``: pair index of each ordered joint pair (-1 on the diagonal).
    optimistic
        ``optimistic(C) -> Sequence``: an order over ``C`` as given (no leg avoided).
    plan
        Plans the given pairs (updates ``C`` and ``known``).
    resequence
        Orders known-first again and plans what that order still needs; returns the Sequence.
    near
        ``near(pairs)``: unknown pairs worth planning with ``pairs`` (their ends' neighbours).
    target
        Relative gap route / optimistic - 1 at which to stop.
    max_rounds
        Bound on the optimistic orders computed.

    Returns
    -------
    (Sequence, GapRounds)
        The best route found (known legs only) and what was done.
    """
    history: list[tuple[float, float]] = []
    planned = 0
    opt_cost = float("nan")
    reason = f"{max_rounds} rounds"
    for _ in range(max_rounds):
        T = optimistic(C)
        opt_cost = float(T.cost)
        history.append((float(seq.cost), opt_cost))
        pairs = order_pairs(T.order, pair_index)
        unknown = [int(p) for p in pairs if not known[p]]
        if not unknown and np.isfinite(opt_cost):
            if opt_cost < seq.cost:
                seq = T
            reason = "optimistic order is known"
            break
        if seq.cost <= (1.0 + target) * opt_cost:
            reason = "within target of the optimistic order"
            break
        todo = sorted(set(unknown) | set(near(unknown)))
        log.info(
            "gap round %d: route %.1f mm, optimistic %.1f mm (+%.2f %%), planning %d legs",
            len(history),
            seq.cost,
            opt_cost,
            100.0 * (seq.cost / opt_cost - 1.0),
            len(todo),
        )
        plan(todo)
        planned += len(todo)
        new = resequence()
        if new.cost <= seq.cost or not _only_known(seq, known, pair_index):
            seq = new
    return seq, GapRounds(len(history), planned, opt_cost, reason, tuple(history))


def _only_known(seq: Any, known: NDArray[np.bool_], pair_index: NDArray[np.intp]) -> bool:
    return bool(known[order_pairs(seq.order, pair_index)].all())
