"""Interlocked zones: order every pair of conflicting motions of two robots, under any timing.

:func:`weldplan.multi.interference.find_interference` lists the pairs of motions of two robots
whose swept robots come closer than the clearance. Two such motions must never run at the same
time, whatever the robots' speeds and waits: one must be over before the other starts. An
:class:`~weldplan.multi.schedule.Interlock` gives that order in the programs: robot ``first``
signals at rest at its stop row ``release_row``, robot ``second`` waits for the signal at rest at
its stop row ``wait_row`` before it leaves. This module chooses the interlocks (issue 30, item 4;
the shape of Åblad et al., IEEE T-ASE 2022, and of Spensieri et al., IEEE T-ASE 2016: shared
zones entered by one robot at a time, the waits in the cycle time).

Events and happens-before
-------------------------
Robot ``r``'s motions ``0 .. 2S`` (:class:`~weldplan.multi.interference.Motion`: rests at its
stops and moves between them) run between its events ``0 .. 2S + 1``: motion ``m`` starts at
event ``m`` and ends at event ``m + 1``; event ``2i`` is the arrival at stop ``i`` (event 0: the
cycle's start), ``2i + 1`` the departure from it (event ``2S + 1``: the cycle's end, never
followed). An interlock is the edge from ``first``'s arrival at ``release_row`` to ``second``'s
departure from ``wait_row``. Event ``u`` happens before event ``v`` under every timing when a
path of program order and interlock edges leads from ``u`` to ``v``; two motions are **ordered**
when the end of one happens before the start of the other. This module keeps the relation as
vector clocks (per event, the last event of every robot that happens before it).

The choice
----------
1. The conflicts of a pair of robots are grouped into **zones**: the connected groups of conflict
   cells ``(motion of a, motion of b)``, consecutive motions of each robot adjacent. A zone costs
   one interlock: all of ``a``'s motions of the zone before all of ``b``'s, or the reverse.
2. Zones are taken in the order of the nominal schedule (the earliest start of their motions);
   a zone already ordered by the interlocks chosen costs nothing. Its order is the one the
   nominal schedule, with the waits of the interlocks chosen so far, suggests (the robot that
   gets there first goes first), unless that closes a cycle of the programs' order and the
   interlocks already chosen (a deadlock) or is impossible (a robot cannot leave its first rest
   after another, nor release from its last), then the other. When both close a cycle, each cell
   of the zone is ordered alone the same way; a cell that cannot be ordered either way is a
   :class:`~weldplan.errors.PlanningError` naming the robots and rows (or, not ``strict``,
   listed in :attr:`ZonePlan.unresolved`).
3. Interlocks implied by the others (transitive reduction) are dropped; the rest are numbered in
   the order of their nominal release: zone ``Z<k>``, signal ``k``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from weldplan.errors import PlanningError
from weldplan.multi.interference import Conflict, Interference, Motion
from weldplan.multi.schedule import Interlock

log = logging.getLogger(__name__)

#: an edge of happens-before: (robot, arrival event, robot, departure event)
Edge = tuple[int, int, int, int]


@dataclass(frozen=True)
class Zone:
    """A group of conflicting motions of two robots, given one order.

    Attributes
    ----------
    first, second
        Robot indices: ``first``'s motions of the zone run before ``second``'s.
    first_motions, second_motions
        ``(lo, hi)`` motion indices (:class:`~weldplan.multi.interference.Motion`) of each.
    cells
        Conflicting motion pairs in it.
    reversed
        The nominal order closed a cycle (or was impossible): the other order was taken.
    """

    first: int
    first_motions: tuple[int, int]
    second: int
    second_motions: tuple[int, int]
    cells: int
    reversed: bool = False


@dataclass(frozen=True, eq=False)
class ZonePlan:
    """The interlocks that order every conflict.

    Attributes
    ----------
    interlocks
        Numbered ``Z1``/signal 1 on, by nominal release time.
    zones
        Every zone that needed an order (those already ordered by others included).
    conflicts
        Conflicting motion pairs ordered.
    dropped
        Interlocks removed as implied by the others.
    unresolved
        Conflicts no interlock can order (only with ``strict=False``; else a PlanningError).
    """

    interlocks: tuple[Interlock, ...]
    zones: tuple[Zone, ...]
    conflicts: int
    dropped: int
    unresolved: tuple[Conflict, ...] = ()

    def line(self) -> str:
        """One line: conflicts, zones, interlocks."""
        rev = sum(z.reversed for z in self.zones)
        left = f", {len(self.unresolved)} that no interlock can order" if self.unresolved else ""
        return (
            f"{self.conflicts} conflicting motion pairs in {len(self.zones)} zones, "
            f"{len(self.interlocks)} interlocks ({self.dropped} implied dropped, "
            f"{rev} zones against the nominal order to avoid a deadlock){left}"
        )


# ---------------------------------------------------------------------------- happens-before
def happens_before(sizes: list[int], edges: list[Edge]) -> list[np.ndarray]:
    """Vector clocks: per robot ``(E_r, R) int`` arrays, ``vc[r][e, s]`` the last event of robot
    ``s`` that happens before (or is) event ``e`` of robot ``r`` (-1: none).

    Parameters
    ----------
    sizes
        Events per robot (``2S + 2``; 0 for an idle robot).
    edges
        ``(a, u, b, v)``: event ``u`` of ``a`` happens before event ``v`` of ``b``.

    Raises
    ------
    PlanningError
        The edges close a cycle with the programs' order (a deadlock).
    """
    R = len(sizes)
    vc = [np.full((n, R), -1, dtype=np.int64) for n in sizes]
    for r, n in enumerate(sizes):
        vc[r][:, r] = np.arange(n)
    into: dict[int, list[Edge]] = {}
    for e in edges:
        into.setdefault(e[2], []).append(e)
    for _ in range(len(edges) + 2):
        changed = False
        for r in range(R):
            inc = vc[r].copy()
            for a, u, _, v in into.get(r, ()):
                inc[v] = np.maximum(inc[v], vc[a][u])
            new = np.maximum.accumulate(inc, axis=0) if len(inc) else inc
            if not np.array_equal(new, vc[r]):
                vc[r], changed = new, True
        if any(len(v) and np.any(v[:, r] > np.arange(len(v))) for r, v in enumerate(vc)):
            break
        if not changed:
            return vc
    raise PlanningError(f"the interlocks wait on each other in a circle (deadlock): {edges}")


def ordered(vc: list[np.ndarray], a: int, x: int, b: int, y: int) -> bool:
    """Whether motion ``x`` of ``a`` and motion ``y`` of ``b`` never run at the same time."""
    return bool(vc[b][y, a] >= x + 1 or vc[a][x, b] >= y + 1)


def _closes_cycle(vc: list[np.ndarray], edge: Edge) -> bool:
    a, u, b, v = edge
    return bool(vc[a][u, b] >= v)


def _edge(sizes: list[int], a: int, x_hi: int, b: int, y_lo: int) -> Edge | None:
    """The interlock edge that puts ``a``'s motions up to ``x_hi`` before ``b``'s from ``y_lo``:
    ``a``'s first arrival at or after the end of ``x_hi``, ``b``'s last departure at or before
    the start of ``y_lo``; ``None`` when there is none."""
    u = x_hi + 1 if (x_hi + 1) % 2 == 0 else x_hi + 2
    v = y_lo if y_lo % 2 == 1 else y_lo - 1
    if u > sizes[a] - 2 or v < 1:
        return None
    return (a, u, b, v)


# ---------------------------------------------------------------------------- nominal times
def nominal_times(motions: tuple[tuple[Motion, ...], ...], edges: list[Edge]) -> list[np.ndarray]:
    """Per robot ``(2S + 1,)`` s: when each motion starts, each robot running its own timing and
    waiting where an edge holds it (released after the weld at the release stop), as
    :func:`weldplan.multi.schedule.station_schedule` counts."""
    dur = [np.array([m.end - m.start for m in ms]) for ms in motions]
    into: dict[int, list[Edge]] = {}
    for e in edges:
        into.setdefault(e[2], []).append(e)
    t = [np.concatenate([[0.0], np.cumsum(d)]) for d in dur]
    for _ in range(len(edges) + 2):
        changed = False
        for r, d in enumerate(dur):
            hold: dict[int, float] = {}
            for a, u, _, v in into.get(r, ()):  # released after its dwell at the release stop
                hold[v] = max(hold.get(v, -np.inf), t[a][u] + dur[a][u])
            new = t[r].copy()
            for e in range(1, len(new)):
                new[e] = max(new[e - 1] + d[e - 1], hold.get(e, -np.inf))
            if not np.allclose(new, t[r], rtol=0, atol=1e-12):
                t[r], changed = new, True
        if not changed:
            break
    return [x[:-1] for x in t]


# ---------------------------------------------------------------------------- zones
def _components(conflicts: list[Conflict]) -> list[list[Conflict]]:
    """Connected groups of conflict cells of one pair of robots (8-neighbours)."""
    left = {(c.x, c.y): c for c in conflicts}
    out = []
    while left:
        seed = next(iter(left))
        stack, comp = [seed], []
        left_cell = left.pop(seed)
        comp.append(left_cell)
        while stack:
            x, y = stack.pop()
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    k = (x + dx, y + dy)
                    if k in left:
                        comp.append(left.pop(k))
                        stack.append(k)
        out.append(comp)
    return out


def _zone_edges(
    comp: list[Conflict], motions: Any, times: list[np.ndarray], edges: list[Edge],
    unresolved: list[Conflict] | None,
) -> tuple[list[Edge], Zone] | None:  # fmt: skip
    """The edge(s) that order zone ``comp`` given ``edges``, and its :class:`Zone`; ``None``
    when ``edges`` already order it. ``unresolved``: where to put the cells no order can part
    (``None``: a PlanningError)."""
    sizes = _sizes(motions)
    vc = happens_before(sizes, edges)
    a, b = comp[0].a, comp[0].b
    if all(ordered(vc, a, c.x, b, c.y) for c in comp):
        return None
    xs, ys = [c.x for c in comp], [c.y for c in comp]
    box = ((min(xs), max(xs)), (min(ys), max(ys)))
    a_first = times[a][box[0][0]] <= times[b][box[1][0]]
    for k, first in enumerate((a_first, not a_first)):
        (f, (f_lo, f_hi)), (s, (s_lo, s_hi)) = ((a, box[0]), (b, box[1]))[:: 1 if first else -1]
        edge = _edge(sizes, f, f_hi, s, s_lo)
        if edge is not None and not _closes_cycle(vc, edge):
            return [edge], Zone(f, (f_lo, f_hi), s, (s_lo, s_hi), len(comp), k == 1)
    new = _cell_edges(comp, motions, times, edges, unresolved)
    return new, Zone(a, box[0], b, box[1], len(comp), True)


def _sizes(motions: Any) -> list[int]:
    """Events per robot: one more than its motions (0: an idle robot)."""
    return [len(m) + 1 if len(m) else 0 for m in motions]


def _what(motion: Motion) -> str:
    if motion.kind == "rest":
        return f"at rest at row {motion.start_row}"
    return f"moving rows {motion.start_row} -> {motion.end_row}"


def _cell_edges(
    comp: list[Conflict], motions: Any, times: list[np.ndarray], edges: list[Edge],
    unresolved: list[Conflict] | None,
) -> list[Edge]:  # fmt: skip
    """A zone whose block order closes a cycle either way: each cell ordered alone."""
    sizes = _sizes(motions)
    new: list[Edge] = []
    for c in sorted(comp, key=lambda c: (times[c.a][c.x], c.x, c.y)):
        vc = happens_before(sizes, edges + new)
        if ordered(vc, c.a, c.x, c.b, c.y):
            continue
        tries = [(c.a, c.x, c.b, c.y), (c.b, c.y, c.a, c.x)]
        if times[c.a][c.x] > times[c.b][c.y]:
            tries.reverse()
        for f, fx, s, sy in tries:
            e = _edge(sizes, f, fx, s, sy)
            if e is not None and not _closes_cycle(vc, e):
                new.append(e)
                break
        else:
            if unresolved is not None:
                unresolved.append(c)
                continue
            raise PlanningError(
                f"robots {c.a + 1} and {c.b + 1} cannot be kept apart by interlocks: robot "
                f"{c.a + 1} {_what(motions[c.a][c.x])} and robot {c.b + 1} "
                f"{_what(motions[c.b][c.y])} come within {c.distance:.1f} mm ({c.bodies}), and "
                "the programs' order and the other interlocks make them overlap"
            )
    return new


def resolve_zones(interference: Interference, *, strict: bool = True) -> ZonePlan:
    """The interlocks that order every conflict of ``interference`` (module docstring).

    Parameters
    ----------
    interference
        What :func:`~weldplan.multi.interference.find_interference` found.
    strict
        ``False``: conflicts no interlock can order are listed in :attr:`ZonePlan.unresolved`
        (and the others ordered) instead of raising.

    Raises
    ------
    PlanningError
        ``strict`` and two motions that no interlock can order (e.g. two robots' start
        configurations closer than the clearance).
    """
    motions = interference.motions
    sizes = _sizes(motions)
    by_pair: dict[tuple[int, int], list[Conflict]] = {}
    for c in interference.conflicts:
        by_pair.setdefault((c.a, c.b), []).append(c)
    comps = [comp for cs in by_pair.values() for comp in _components(cs)]
    t0 = nominal_times(motions, [])
    comps.sort(key=lambda cp: min(min(t0[c.a][c.x], t0[c.b][c.y]) for c in cp))
    edges: list[Edge] = []
    zones: list[Zone] = []
    unresolved: list[Conflict] | None = None if strict else []
    for comp in comps:
        got = _zone_edges(comp, motions, nominal_times(motions, edges), edges, unresolved)
        if got is not None:
            edges += got[0]
            zones.append(got[1])
    kept, dropped = _reduce(sizes, edges)
    vc = happens_before(sizes, kept)
    left = tuple(unresolved or ())
    bad = [
        c for c in interference.conflicts
        if not ordered(vc, c.a, c.x, c.b, c.y) and not any(c is u for u in left)
    ]  # fmt: skip
    if bad:  # the construction orders each; a failure here is a bug, said plainly
        raise PlanningError(f"interlocks leave {len(bad)} conflicts unordered: {bad[:3]}")
    locks = _interlocks(motions, kept)
    log.info("zones: %d conflicts, %d zones, %d interlocks", len(interference.conflicts),
             len(zones), len(locks))  # fmt: skip
    return ZonePlan(locks, tuple(zones), len(interference.conflicts), dropped, left)


def _reduce(sizes: list[int], edges: list[Edge]) -> tuple[list[Edge], int]:
    """Drop every edge implied by the others (transitive reduction), the latest first."""
    kept = list(edges)
    for e in reversed(edges):
        rest = [k for k in kept if k != e]
        if _closes_cycle_free(sizes, rest, e):
            kept = rest
    return kept, len(edges) - len(kept)


def _closes_cycle_free(sizes: list[int], rest: list[Edge], e: Edge) -> bool:
    """Whether ``rest`` alone already puts ``e``'s source before its target."""
    a, u, b, v = e
    return bool(happens_before(sizes, rest)[b][v, a] >= u)


def _interlocks(
    motions: tuple[tuple[Motion, ...], ...], edges: list[Edge]
) -> tuple[Interlock, ...]:
    """The edges as numbered interlocks, by nominal release time."""
    t = nominal_times(motions, edges)
    order = sorted(edges, key=lambda e: (t[e[0]][e[1]], e))
    out = []
    for k, (a, u, b, v) in enumerate(order, start=1):
        release = motions[a][u].start_row  # the rest at the arrival's stop
        wait = motions[b][v - 1].start_row  # the rest at the departure's stop
        out.append(Interlock(f"Z{k}", a, release, b, wait, k))
    return tuple(out)
