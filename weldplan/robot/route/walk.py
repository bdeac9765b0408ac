"""The robot's joint route assembled: the welds it serves, in route order, joined by the
route's own legs or by detours (:class:`weldplan.robot.route.Detour`).

:func:`assemble` walks the welds the robot serves (status ``ok``) in route order. The leg from
one served weld ``a`` to the next ``b`` is first the route's own: its waypoints'
configurations, checked with the tool's contact zone exempt (the TCP is on the verified route).
When that is blocked, the leg becomes a detour: leave ``a`` (a gun exit or a retract), transfer,
approach ``b`` (:mod:`weldplan.robot.route.replan`).

When no detour is found, ``b`` is dropped (status ``collision``; its ``detail`` names the body
that blocked the route's own leg and the cause: which end has no free gun exit or retract, or
what blocks the straight transfer when no tucked arm or OMPL run found one;
:data:`~weldplan.robot.route.walkstats.CAUSES`) and the next served weld is tried from ``a``.

*Back along the path.* When no detour from ``a`` reaches ``b``, the robot may go back the way it
came: along the assembled path (its own motions, reversed, each checked as it was) to a *hub*,
the end of an earlier transfer (a clear configuration from which OMPL found a way; the latest
:data:`RETRACE_HUBS`, not ``a``'s own approach, which is where ``a`` is left from), and detour
from there (transfer, approach ``b``). ``a`` stays served; the rows going back are labelled with
``a``'s row and are not exact. After :data:`RETRACE_TRIES` failures in a row from one weld, it
stops trying.

*A weld the robot cannot go on from.* When :data:`TRAP_FAILS` welds in a row cannot be reached
from ``a``, ``a`` itself may be the trap: its exit leads into a pocket no transfer leaves (on
car2_200 with car2_50's base, one such weld cost all 106 welds tried after it, one OMPL run
each, before the 15 min time-box). ``a`` is then set aside and those welds are tried again from
the weld served before it: when one of them is reached, ``a`` is dropped (its ``detail`` says
which welds it could not reach) and the rest are tried on from there; when none is, ``a`` is put
back and they stay dropped. The test is repeated after every :data:`TRAP_FAILS` more failures
from ``a``, with the latest ones, at most :data:`TRAP_TESTS` times (the welds right after ``a``
may be hard to reach from anywhere: on that car2_200 run Z4L-3's successors Z4L-2 and Z4L-1
were reached from neither Z4L-3 nor the weld before it).

*The first served weld* has no weld before it: the robot comes to it from wherever it is. It is
tested as the trap by starting the path again at the first welds of the window (the robot may
start anywhere) and trying the others from it: when one is reached, the first weld is dropped
and the walk goes on from there; else it is put back. So one weld the robot can enter but not
leave costs that weld wherever it stands in the route, never the rest (before, a 40-spot station
whose first weld was such a trap served 2 of its 40 welds).

*The budget.* Every transfer tried is charged to the weld it leads to, and no weld gets more
than :data:`TRANSFERS_PER_WELD` (then it is dropped untried): the walk over ``n`` welds tries at
most ``n * TRANSFERS_PER_WELD`` transfers, each with its own bounded OMPL budget
(:class:`~weldplan.robot.route.Detour`). The work (transfers tried and found, OMPL runs, tries
back along the path, trap tests) and every weld left out with its cause are reported
(:class:`~weldplan.robot.route.WalkStats`).

*The head.* The route's rows before the first served weld are its own when free; when they are
blocked, they are held at the clear end of that weld's approach (its gun exit or retract,
reversed: the robot starts there), or, with none, at the weld's own configuration.

Welds the path passes without serving keep a row on it that is not exact (the program passes
them without welding): the detour's joint polyline is subdivided where it has fewer inner rows
than such welds (points on its own segments: the motion is unchanged). The motions of the
route's own legs are checked with the contact zone exempt where the caller says (``zone=``:
every one on the point-tip route; only near the spots on a route along the gun's transitions,
:mod:`weldplan.robot.route.gunpath`), those of the retract/approach with it exempt, those of the
transfer without (``zone`` in the result). The caller checks the assembled path again (the
verification).

The tail (the route's rows after the last served weld) is the route's own rows when free; a
blocked tail is replaced by the retract from the last served weld (subdivided, one
point per route row after it, the last the retract configuration), or, with no retract, by the
last served configuration held (the program ends at that weld).
"""

from __future__ import annotations

import dataclasses
import logging
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.robot.collision.selfcollision import hit_words
from weldplan.robot.placement.reach import COLLISION, OK
from weldplan.robot.route.legtrial import LegTrial, leg_hits, leg_trial
from weldplan.robot.route.replan import Detour
from weldplan.robot.route.walkpath import JointPath, add_detour, tail
from weldplan.robot.route.walkstats import (
    BUDGET,
    NO_APPROACH,
    NO_EXIT,
    NO_TRANSFER,
    TRAP,
    Assembled,
    WalkStats,
)

log = logging.getLogger(__name__)

#: welds in a row not reached from one weld before that weld is tested as the trap (module
#: docstring)
TRAP_FAILS = 2
#: hubs (the ends of earlier transfers) a blocked leg may go back to, the latest first
#: (:meth:`_Walk.retrace`; each costs a transfer that may fail)
RETRACE_HUBS = 2
#: failed tries in a row to go back from one weld after which it no longer tries (a base from
#: which every later weld is out of reach would pay :data:`RETRACE_HUBS` more failing transfers
#: for each of them)
RETRACE_TRIES = 2
#: the most times one weld is tested as the trap (each test costs up to :data:`TRAP_FAILS`
#: transfers that may fail: a bound on what a route whose later welds no one reaches pays)
TRAP_TESTS = 3
#: transfers (:meth:`~weldplan.robot.route.Detour.transfer` calls) tried towards one weld, at
#: most (module docstring): from the path's end and back along it to the hubs (1 +
#: :data:`RETRACE_HUBS`), once in a trap test, and once more with its hubs when a trap before
#: it was set aside; then it is dropped untried. The walk over ``n`` welds tries at most
#: ``n * TRANSFERS_PER_WELD`` transfers, each with its own bounded OMPL budget
TRANSFERS_PER_WELD = 2 * (1 + RETRACE_HUBS) + 1

#: a place in a :class:`JointPath` (its rows, the zone flag of its last row) and how many legs
#: had been detoured then
Mark = tuple[int, bool, int]


def assemble(
    det: Detour,
    q: NDArray[np.float64],
    exact: NDArray[np.bool_],
    branch: NDArray[np.int64],
    rows: NDArray[np.int64],
    status: list[str],
    detail: list[str],
    ids: tuple[str, ...],
    zone: NDArray[np.bool_] | None = None,
    blocked: set[int] | None = None,
) -> Assembled:
    """The joint route with blocked legs detoured (module docstring).

    Parameters
    ----------
    q, exact, branch
        ``(m, 6)`` rad, ``(m,)``, ``(m,)``: one row per route waypoint.
    rows
        ``(n,)``: the route rows of the welds, in route order.
    status, detail
        Per weld; updated in place for the welds dropped.
    ids
        The welds' ids (for the details).
    zone
        ``(m - 1,) bool``: the route's own motions on which the contact zone is exempt (default
        every one; a route along the gun's transitions exempts it only near the spots).
    blocked
        The route's own motions the caller's check of ``q`` (same checker, same ``zone``) found
        blocked, every one: a leg with none of them is not checked again. ``None``: each leg is
        checked here.
    """
    served = [k for k in range(len(rows)) if status[k] == OK]
    own = np.ones(max(len(q) - 1, 0), dtype=bool) if zone is None else np.asarray(zone, bool)
    own = np.append(own, True)  # own[i]: the motion leaving route row i (the last: none)
    served_exact = np.zeros(len(q), dtype=bool)
    served_exact[rows[served]] = True
    # a weld row that is not served is passed, never exact
    ex = exact & (served_exact | ~np.isin(np.arange(len(q)), rows))
    w = _Walk(det, q, ex, branch, rows, own, blocked, status, detail, ids)
    if not served:
        for i in range(len(q)):
            w.out.add(q[i], i, bool(ex[i]), int(branch[i]), bool(own[i]))
        return w.result()
    w.start_trial(served)
    w.head(served[0])
    a, fails = served[0], []
    queue = deque(served[1:])
    while queue:
        b = queue.popleft()
        mark = w.mark()
        why = w.join(a, b)
        if why is None:
            w.prev[b] = (a, mark)
            a, fails = b, []
            continue
        w.drop(b, *why)
        fails.append(b)
        if len(fails) % TRAP_FAILS == 0 and w.tested.get(a, 0) < TRAP_TESTS:
            test = w.without if a in w.prev else w.restart  # a without prev: the first weld
            a, fails, again = test(a, fails)
            queue.extendleft(reversed(again))
    tail(det, w.out, q, ex, branch, int(rows[a]), own, blocked)
    return w.result()


@dataclass
class _Walk:
    """The state of :func:`assemble`'s walk: the path so far, the welds joined and how."""

    det: Detour
    q: NDArray[np.float64]
    ex: NDArray[np.bool_]
    branch: NDArray[np.int64]
    rows: NDArray[np.int64]
    own: NDArray[np.bool_]
    blocked: set[int] | None
    status: list[str]
    detail: list[str]
    ids: tuple[str, ...]
    out: JointPath = field(default_factory=JointPath)
    replanned: list[int] = field(default_factory=list)
    #: per weld joined: the weld it was joined from and the path's :data:`Mark` before its leg
    prev: dict[int, tuple[int, Mark]] = field(default_factory=dict)
    #: per weld, how many times it was tested as the trap
    tested: dict[int, int] = field(default_factory=dict)
    #: rows of the path at the ends of its transfers (clear configurations OMPL connected)
    hubs: list[tuple[int, int]] = field(default_factory=list)
    #: per weld, the tries in a row to go back from it that failed (:data:`RETRACE_TRIES`)
    retraced_from: dict[int, int] = field(default_factory=dict)
    #: per weld, the transfers tried towards it (:data:`TRANSFERS_PER_WELD`)
    tries: dict[int, int] = field(default_factory=dict)
    #: per weld dropped, the cause (:data:`CAUSES`)
    cause: dict[int, str] = field(default_factory=dict)
    #: counters of :class:`WalkStats`
    count: dict[str, int] = field(default_factory=dict)
    #: per route row of a weld, its way off (:meth:`leave`, cached: the trial asks it first)
    left: dict[int, NDArray[np.float64] | None] = field(default_factory=dict)
    #: per two route rows, :meth:`pair`'s answer (cached: the trial asks it first)
    pairs: dict[tuple[int, int], tuple[Any, Any, Any]] = field(default_factory=dict)
    #: the transfer trial before the walk (:meth:`start_trial`)
    trial: LegTrial | None = None

    def leave(self, r: int) -> NDArray[np.float64] | None:
        """:meth:`Detour.leave` of the weld at route row ``r`` (its configuration and branch on
        the route), cached: the same rows, computed once."""
        if r not in self.left:
            self.left[r] = self.det.leave(self.q[r], r, int(self.branch[r]))
        return self.left[r]

    def pair(self, ia: int, ib: int) -> tuple[Any, Any, Any]:
        """``(way off a, way into b, transfer)`` between the welds at route rows ``ia`` and
        ``ib`` without a planner: their first ways off (:meth:`leave`) joined by a straight or
        tucked transfer, else another pair of their :data:`~weldplan.robot.route.replan.WAYS_OFF`
        ways (:meth:`~weldplan.robot.route.Detour.ways_off`, the first ways' sides first); the
        transfer ``None`` when none joins (then the first ways, for OMPL), a way ``None`` when
        that weld has none. Cached."""
        if (ia, ib) in self.pairs:
            return self.pairs[(ia, ib)]
        la, lb = self.leave(ia), self.leave(ib)
        got: tuple[Any, Any, Any] = (la, lb, None)
        if la is not None and lb is not None:
            mid = self.det.joins_directly(la[-1], lb[-1])
            if mid is not None:
                got = (la, lb, mid)
            else:
                got = self._other_pair(ia, ib, la, lb)
        self.pairs[(ia, ib)] = got
        return got

    def _other_pair(self, ia: int, ib: int, la: NDArray, lb: NDArray) -> tuple[Any, Any, Any]:
        """:meth:`pair` past the first ways: the other ways off ``ia`` and into ``ib``, pairs
        in order of the sum of their places (the first ways' sides first)."""
        d = self.det
        wa = d.ways_off(self.q[ia], ia, int(self.branch[ia]), la)
        wb = d.ways_off(self.q[ib], ib, int(self.branch[ib]), lb)
        order = sorted(((i, j) for i in range(len(wa)) for j in range(len(wb))),
                       key=lambda ij: (ij[0] + ij[1], ij))  # fmt: skip
        for i, j in order[1:]:
            mid = d.joins_directly(wa[i][-1], wb[j][-1])
            if mid is not None:
                self.tally("other_ways")
                return wa[i], wb[j], mid
        return la, lb, None

    def start_trial(self, served: list[int]) -> None:
        """Run the transfer trial on the legs between the ``served`` welds
        (:func:`~weldplan.robot.route.legtrial.leg_trial`), say at once which it leaves split,
        and give each split leg its share of the route's OMPL retries
        (:meth:`~weldplan.robot.route.legtrial.LegTrial.retry_share`)."""
        d = self.det
        self.trial = leg_trial(d, self.q, self.rows, served, self.own, self.blocked, self.pair)
        share = self.trial.retry_share(d.retry_total_checks, d.retry_leg_checks)
        self.det = dataclasses.replace(d, retry_leg_checks=share)  # same ompl and left_by dicts
        if self.trial.split:
            log.warning("robot walk: the transfer trial on the route at this base: %s; each is "
                        "left to OMPL with up to %d retry checks", self.trial.describe(self.ids),
                        share)  # fmt: skip

    def mark(self) -> Mark:
        return (*self.out.mark(), len(self.replanned))

    def tally(self, key: str, by: int = 1) -> None:
        self.count[key] = self.count.get(key, 0) + by

    def result(self) -> Assembled:
        """The assembled route and the walk's :class:`WalkStats`."""
        o = self.det.ompl
        stats = WalkStats(
            per_weld=TRANSFERS_PER_WELD,
            ompl_runs=int(o.get("runs", 0)),
            ompl_solved=int(o.get("solved", 0)),
            ompl_cpu_s=round(float(o.get("s", 0.0)), 3),
            dropped=tuple(
                (self.ids[k], self.cause[k])
                for k in sorted(self.cause)
                if self.status[k] != OK  # fmt: skip
            ),
            legs_blocked=0 if self.trial is None else self.trial.blocked,
            split_legs=() if self.trial is None else self.trial.names(self.ids),
            retry_share=int(self.det.retry_leg_checks),
            **self.count,
        )
        q, row, exact, branch, zone = self.out.arrays()
        return Assembled(q, row, exact, branch, zone, tuple(self.replanned), stats)

    def head(self, k: int) -> None:
        """Start the path at the first served weld ``k`` (module docstring): the route's own
        rows up to it when free, else the rows before it held at the clear end of ``k``'s
        approach (a gun exit or a retract, reversed), else at ``k``'s configuration."""
        rk = int(self.rows[k])
        q, br, own = self.q, self.branch, self.own
        if rk == 0 or not leg_hits(self.det, q, own, 0, rk, self.blocked):
            for i in range(rk + 1):
                self.out.add(q[i], i, bool(self.ex[i]), int(br[i]), bool(own[i]))
            return
        lv = self.leave(rk)
        A = q[rk][None] if lv is None else lv[::-1]  # the approach, its clear end first
        pb = self.det.robot.branch_of(A)
        for i in range(rk):  # held: no motion (at the weld itself, its contact zone exempt)
            self.out.add(A[0], i, False, int(pb[0]), zone=lv is None)
        for p, b in zip(A[1:], pb[1:], strict=True):
            self.out.add(p, rk - 1, False, int(b), zone=False)
        self.out.zone[-1] = True  # approach -> weld: contact zone exempt
        self.out.add(q[rk], rk, bool(self.ex[rk]), int(br[rk]), bool(own[rk]))
        log.info("weld %s: the robot starts at its approach (the route's rows before it are "
                 "blocked)", self.ids[k])  # fmt: skip

    def join(self, a: int, b: int, retrace: bool = True) -> tuple[str, str] | None:
        """Append the leg from weld ``a`` (the path's end) to weld ``b`` and ``b`` itself:
        the route's own rows when free, else a detour. ``None`` when done, else ``(cause,
        why)`` (the path unchanged; cause one of :data:`CAUSES`)."""
        ia, ib = int(self.rows[a]), int(self.rows[b])
        q, br, own = self.q, self.branch, self.own
        hits = leg_hits(self.det, q, own, ia, ib, self.blocked)
        if not hits:
            self.out.zone[-1] = bool(own[ia])
            for i in range(ia + 1, ib + 1):
                self.out.add(q[i], i, bool(self.ex[i]), int(br[i]), bool(own[i]))
            return None
        got, why = self.detour(a, b)
        if got is None:
            if retrace and self.retraced_from.get(a, 0) < RETRACE_TRIES and self.retrace(a, b):
                return None
            return why[0], f"{hits[0].body} on the leg from weld {self.ids[a]}; {why[1]}"
        n0 = len(self.out.q)
        add_detour(self.out, self.det.robot, got[0], ia, ib, self.rows, q, br)
        self.replanned.append(a)
        self._hubs_at(n0, got[1:], (-1, b))
        return None

    def detour(self, a: int, b: int) -> tuple[Any, tuple[str, str]]:
        """``((path, transfer start, transfer end), None)`` of a detour from weld ``a`` to
        weld ``b`` (leave ``a``, transfer, approach ``b``; rad), else ``(None, (cause, why))``:
        which end has no way off its weld, or why the transfer failed. The transfer: one that
        needs no planner between any of their ways off (:meth:`pair`), else OMPL's from the
        first ways (:meth:`transfer`)."""
        ia, ib = int(self.rows[a]), int(self.rows[b])
        q = self.q
        if self.tries.get(b, 0) >= TRANSFERS_PER_WELD:  # untried: not even its ends
            return self.transfer(q[ia], q[ib], b, "")
        la, lb, mid = self.pair(ia, ib)
        if la is None:
            return None, (NO_EXIT, f"weld {self.ids[a]} has no free gun exit or retract")
        if lb is None:
            return None, (NO_APPROACH, f"weld {self.ids[b]} has no free gun exit or retract")
        if mid is not None:  # a transfer tried and found, no planner
            self.tries[b] = self.tries.get(b, 0) + 1
            self.tally("transfers")
            self.tally("transfers_found")
        else:
            mid, why = self.transfer(la[-1], lb[-1], b, f"weld {self.ids[a]}'s exit")
            if mid is None:
                return None, why
        return (np.vstack([la[:-1], mid, lb[:-1][::-1]]), la[-1], lb[-1]), ("", "")

    def transfer(self, qa: NDArray, qb: NDArray, b: int, src: str) -> tuple[Any, tuple[str, str]]:
        """``(path, _)`` of :meth:`Detour.transfer` ``qa -> qb`` (the approach of weld ``b``),
        within ``b``'s :data:`TRANSFERS_PER_WELD`; else ``(None, (cause, why))``: the budget
        spent, or no transfer and what blocks the straight move (``src`` names ``qa``)."""
        if self.tries.get(b, 0) >= TRANSFERS_PER_WELD:
            return None, (BUDGET, f"its {TRANSFERS_PER_WELD} transfers were spent")
        self.tries[b] = self.tries.get(b, 0) + 1
        self.tally("transfers")
        runs = self.det.ompl.get("runs", 0)
        mid = self.det.transfer(qa, qb)
        if mid is not None:
            self.tally("transfers_found")
            return mid, ("", "")
        hits = self.det.checker.path_hits(np.array([qa, qb]), np.zeros(1, bool), first_only=True)
        straight = hit_words(hits[0].body) if hits else "it leaves the IK branch"
        n = int(self.det.ompl.get("runs", 0) - runs)
        return None, (
            NO_TRANSFER,
            f"no transfer from {src} to weld {self.ids[b]}'s approach (straight: {straight}; "
            f"no tucked arm; OMPL {n} run(s), unsolved)",
        )

    def _hubs_at(self, n0: int, confs: tuple[NDArray, ...], owners: tuple[int, ...]) -> None:
        """Record as hubs the rows from ``n0`` on that equal ``confs`` (a transfer's ends: clear
        configurations from which OMPL found a way), each with the weld it approaches (-1:
        none; a weld's approach is also where it is left from, no way round it)."""
        for c, k in zip(confs, owners, strict=True):
            for i in range(n0, len(self.out.q)):
                if np.array_equal(self.out.q[i], c):
                    self.hubs.append((i, k))
                    break

    def retrace(self, a: int, b: int) -> bool:
        """Reach weld ``b`` from weld ``a`` (the path's end) by going back along the path to one
        of the last :data:`RETRACE_HUBS` hubs and detouring from there (module docstring);
        whether that worked (rows appended, else the path unchanged)."""
        ia, ib = int(self.rows[a]), int(self.rows[b])
        end = len(self.out.q) - 1
        hubs: list[int] = []
        for h, k in reversed(self.hubs):  # the latest first, not a's own, each place once
            if h < end and k != a and not any(np.array_equal(self.out.q[h], self.out.q[g])
                                              for g in hubs):  # fmt: skip
                hubs.append(h)
        hubs = hubs[:RETRACE_HUBS]
        lb = self.leave(ib) if hubs else None
        if lb is None:
            return False
        self.retraced_from[a] = self.retraced_from.get(a, 0) + 1
        self.tally("retraces")
        for h in hubs:
            mid, _ = self.transfer(self.out.q[h], lb[-1], b, "a hub")
            if mid is None:
                continue
            out, zones = self.out, list(self.out.zone)
            for j in range(end - 1, h, -1):  # back along the path: its own motions reversed,
                out.zone[-1] = zones[j]  # each checked as it was (zones[j]: j -> j + 1)
                out.add(out.q[j], ia, False, out.branch[j])
            n0 = len(out.q)
            P = np.vstack([mid, lb[:-1][::-1]])  # mid[0]: the hub, reached by the motion h + 1 -> h
            add_detour(out, self.det.robot, P, ia, ib, self.rows, self.q, self.branch, zones[h])
            self.replanned.append(a)
            self.retraced_from[a] = 0
            self.tally("retraces_found")
            self._hubs_at(n0, (lb[-1],), (b,))
            log.info("weld %s reached from weld %s back along the path (%d rows)",
                     self.ids[b], self.ids[a], end - h)  # fmt: skip
            return True
        return False

    def drop(self, k: int, cause: str, why: str) -> None:
        self.status[k], self.detail[k], self.cause[k] = COLLISION, why, cause
        log.info("weld %s dropped: %s", self.ids[k], why)

    def _set_aside(self, a: int, fails: list[int], f: int, p: str) -> None:
        """Drop weld ``a`` as the trap: ``fails`` were not reached from it, ``f`` was from
        ``p`` (words)."""
        names = ", ".join(self.ids[k] for k in fails[:5])
        more = f" and {len(fails) - 5} more" if len(fails) > 5 else ""
        self.tally("traps")
        self.drop(
            a,
            TRAP,
            f"the robot cannot go on from this weld: weld(s) {names}{more} after it not reached "
            f"from it; weld {self.ids[f]} reached from {p}",
        )

    def without(self, a: int, fails: list[int]) -> tuple[int, list[int], list[int]]:
        """Test weld ``a`` as the trap (module docstring) with the last :data:`TRAP_FAILS` of
        ``fails`` (the welds dropped in a row from it): ``(the weld the path now ends at, the
        welds dropped in a row from it, the welds to try again next)``."""
        self.tested[a] = self.tested.get(a, 0) + 1
        self.tally("trap_tests")
        p, (n, z, n_rep) = self.prev[a]
        saved, saved_rep, saved_hubs = self.out.cut((n, z)), self.replanned[n_rep:], self.hubs
        del self.replanned[n_rep:]
        self.hubs = [(h, k) for h, k in self.hubs if h < n]
        ra = int(self.rows[a])
        ex_a, self.ex[ra] = bool(self.ex[ra]), False
        window = fails[-TRAP_FAILS:]
        for j, f in enumerate(window):
            mark = self.mark()
            if self.join(p, f, retrace=False) is None:  # a's retrace tried the hubs
                self._set_aside(a, fails, f, f"weld {self.ids[p]}")
                self.prev[f] = (p, mark)
                for k in window[j:]:
                    self.status[k], self.detail[k] = OK, ""
                return f, [], window[j + 1 :]
        self.out.paste(saved)
        self.replanned.extend(saved_rep)
        self.hubs = saved_hubs
        self.ex[ra] = ex_a
        log.info("weld %s kept: neither of %s is reached without it", self.ids[a],
                 ", ".join(self.ids[k] for k in window))  # fmt: skip
        return a, fails, []

    def restart(self, a: int, fails: list[int]) -> tuple[int, list[int], list[int]]:
        """Test the first served weld ``a`` (no weld before it) as the trap: the path starts
        again at the first of the last :data:`TRAP_FAILS` of ``fails`` and the others are tried
        from there (module docstring); returns as :meth:`without`."""
        self.tested[a] = self.tested.get(a, 0) + 1
        self.tally("trap_tests")
        saved, saved_rep, saved_hubs = self.out.cut((0, True)), self.replanned, self.hubs
        self.replanned, self.hubs = [], []
        ra = int(self.rows[a])
        ex_a, self.ex[ra] = bool(self.ex[ra]), False
        window = fails[-TRAP_FAILS:]
        s = window[0]
        self.head(s)
        for j, f in enumerate(window[1:], 1):
            mark = self.mark()
            if self.join(s, f, retrace=False) is None:
                self._set_aside(a, fails, f, f"weld {self.ids[s]}, the first weld without it")
                self.prev[f] = (s, mark)
                self.prev.pop(s, None)  # the first weld now: tested by restart() in turn
                for k in (s, *window[j:]):
                    self.status[k], self.detail[k] = OK, ""
                return f, [], window[j + 1 :]
        self.out.cut((0, True))
        self.out.paste(saved)
        self.replanned, self.hubs = saved_rep, saved_hubs
        self.ex[ra] = ex_a
        log.info("weld %s kept: the path does not go on from %s either", self.ids[a],
                 self.ids[s])  # fmt: skip
        return a, fails, []
