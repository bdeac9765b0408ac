"""When each robot of a station moves, welds and waits: interlocks and the station's schedule.

Several robots share one station; two robots whose motions would meet are kept apart by
**interlocks** (issue 30, item 4): an :class:`Interlock` says that robot ``second`` may not
leave its route row ``wait_row`` before robot ``first`` is at rest at its row ``release_row``
(after the weld there, if it welds there). In the programs this is one signal: ``first`` sets
it on reaching ``release_row`` and ``second`` waits for it before leaving ``wait_row``
(:meth:`Interlock.actions`; KRL ``$OUT``/``WAIT FOR $IN``, RAPID ``SetDO``/``WaitDI``,
written by :mod:`weldplan.io.posts`). Both rows are stop rows of their robot's timed route
(the robot is at rest there), so the signal has one meaning whatever the blending.

:func:`station_schedule` turns every robot's timed route
(:class:`weldplan.robot.program.TimedTrajectory`) and the interlocks into the nominal
:class:`StationSchedule`: each robot runs its own timing and waits where an interlock holds it,
until the robot it waits for is ready. The cycle time is the last robot's end; the waits are
counted in it. Interlocks that wait on each other in a circle (a deadlock) are a
:class:`~weldplan.errors.PlanningError`.

Worst-case timing (any robot early or late at any wait) is not this module's business: the
replay that proves two robots never come closer than the clearance under the interlocks'
semantics returns a :class:`ReplayVerdict`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from weldplan.errors import PlanningError

#: what a robot does during an :class:`Activity`
ACTIVITY_KINDS = ("move", "weld", "wait")


@dataclass(frozen=True)
class Interlock:
    """Robot ``second`` may not leave its route row ``wait_row`` before robot ``first`` is at
    rest at its route row ``release_row`` (after its weld there, if any).

    Attributes
    ----------
    zone
        The shared volume's name (e.g. ``"Z1"``): what the two motions would both occupy.
    first, second
        Robot indices (station order, 0-based), ``first != second``.
    release_row, wait_row
        Rows of the timed routes (:class:`~weldplan.robot.program.TimedTrajectory` rows, the
        program's joint rows) of ``first`` and of ``second``; each a stop row of its robot's
        timed route. :meth:`actions` names them by route row for the programs.
    signal
        The I/O number (>= 1) that carries it: ``first``'s output, ``second``'s input.
    """

    zone: str
    first: int
    release_row: int
    second: int
    wait_row: int
    signal: int

    def __post_init__(self) -> None:
        if self.first == self.second or min(self.first, self.second) < 0:
            raise ValueError(f"interlock {self.zone}: robots {self.first} and {self.second}")
        if self.signal < 1 or min(self.release_row, self.wait_row) < 0:
            raise ValueError(f"interlock {self.zone}: signal {self.signal} or a negative row")

    @property
    def name(self) -> str:
        """The signal's name in the programs, e.g. ``Z1_R1_R2``: zone, releasing robot, waiting
        robot (1-based)."""
        return f"{self.zone}_R{self.first + 1}_R{self.second + 1}"

    def actions(self, rows: Sequence[Any | None]) -> tuple[tuple[int, Any], tuple[int, Any]]:
        """``((first, set action), (second, wait action))``: the two program actions
        (:class:`weldplan.io.posts.program.SignalAction`) with the robot that runs each.

        ``rows``: per robot, the route row of each timed row
        (:attr:`weldplan.robot.program.ProgramBuild.row`; ``None``: the same rows), since a
        program's targets are named by route row."""
        from weldplan.io.posts.program import SignalAction

        def route_row(robot: int, row: int) -> int:
            r = rows[robot]
            return row if r is None else int(np.asarray(r)[row])

        return (
            (
                self.first,
                SignalAction(
                    route_row(self.first, self.release_row), "set", self.signal, self.name
                ),
            ),
            (
                self.second,
                SignalAction(route_row(self.second, self.wait_row), "wait", self.signal, self.name),
            ),
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "zone": self.zone,
            "first": self.first,
            "release_row": self.release_row,
            "second": self.second,
            "wait_row": self.wait_row,
            "signal": self.signal,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Interlock:
        return cls(
            str(d["zone"]),
            int(d["first"]),
            int(d["release_row"]),
            int(d["second"]),
            int(d["wait_row"]),
            int(d["signal"]),
        )


@dataclass(frozen=True)
class Activity:
    """One interval of one robot's cycle.

    Attributes
    ----------
    robot
        Robot index (0-based).
    kind
        One of :data:`ACTIVITY_KINDS`.
    start, end
        s from the station's cycle start, ``start <= end``.
    row
        ``move``: the timed row it moves to; ``weld``, ``wait``: the timed row it rests at
        (:class:`~weldplan.robot.program.TimedTrajectory` rows).
    label
        The weld's id (``weld``), the interlock's name (``wait``), else ``""``.
    """

    robot: int
    kind: str
    start: float
    end: float
    row: int
    label: str = ""

    def __post_init__(self) -> None:
        if self.kind not in ACTIVITY_KINDS or not self.start <= self.end:
            raise ValueError(f"bad activity {self.kind!r} [{self.start}, {self.end}]")

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass(frozen=True)
class StationSchedule:
    """The nominal station cycle: every robot's moves, welds and waits on one clock.

    Attributes
    ----------
    robots
        Robot names, station order.
    activities
        Per robot in time order, robots in order.
    interlocks
        The interlocks the waits come from.
    """

    robots: tuple[str, ...]
    activities: tuple[Activity, ...]
    interlocks: tuple[Interlock, ...] = ()

    def of(self, robot: int) -> tuple[Activity, ...]:
        """Robot ``robot``'s activities, in time order."""
        return tuple(a for a in self.activities if a.robot == robot)

    @property
    def cycle_times(self) -> tuple[float, ...]:
        """s per robot: when it is done (its last activity's end; 0 for an idle robot)."""
        return tuple(max((a.end for a in self.of(r)), default=0.0) for r in range(len(self.robots)))

    @property
    def cycle_time(self) -> float:
        """s: the station's cycle, the last robot's end."""
        return max(self.cycle_times, default=0.0)

    def seconds(self, robot: int, kind: str) -> float:
        """s robot ``robot`` spends in activities of ``kind``."""
        return float(sum(a.duration for a in self.of(robot) if a.kind == kind))

    @property
    def waiting(self) -> tuple[float, ...]:
        """s per robot held at interlocks."""
        return tuple(self.seconds(r, "wait") for r in range(len(self.robots)))

    @property
    def utilisation(self) -> tuple[float, ...]:
        """Per robot, its moving and welding time over the station's cycle (0 when idle)."""
        top = self.cycle_time
        return tuple(
            (self.seconds(r, "move") + self.seconds(r, "weld")) / top if top > 0 else 0.0
            for r in range(len(self.robots))
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "robots": list(self.robots),
            "interlocks": [i.to_dict() for i in self.interlocks],
            "activities": [
                [a.robot, a.kind, round(a.start, 6), round(a.end, 6), a.row, a.label]
                for a in self.activities
            ],
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> StationSchedule:
        acts = tuple(
            Activity(int(r), str(k), float(s), float(e), int(row), str(lab))
            for r, k, s, e, row, lab in d["activities"]
        )
        locks = tuple(Interlock.from_dict(i) for i in d.get("interlocks", ()))
        return cls(tuple(str(n) for n in d["robots"]), acts, locks)


@dataclass(frozen=True)
class ReplayVerdict:
    """What the independent replay of the timed programs under the interlocks found.

    Attributes
    ----------
    ok
        No two robots closer than ``clearance`` under any timing the interlocks allow.
    clearance
        mm asked.
    min_distance
        mm: the smallest robot-robot distance (links and tools) over every pair of motions
        that may overlap in time (``inf`` when no pair may overlap).
    closest
        ``(robot a, row a, robot b, row b)`` where ``min_distance`` was found (the timed rows
        the two robots move to, or rest at), or ``None``.
    pairs
        Pairs of motions (one per robot) that may overlap in time and were checked.
    failures
        One line per pair closer than ``clearance`` (at most a few; empty when ``ok``).
    method
        One line: how the replay sampled the motions and what it checked with.
    """

    ok: bool
    clearance: float
    min_distance: float
    closest: tuple[int, int, int, int] | None
    pairs: int
    failures: tuple[str, ...] = ()
    method: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {
            "ok": self.ok,
            "clearance": self.clearance,
            "min_distance": None if np.isinf(self.min_distance) else self.min_distance,
            "closest": None if self.closest is None else list(self.closest),
            "pairs": self.pairs,
            "failures": list(self.failures),
            "method": self.method,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ReplayVerdict:
        md = d.get("min_distance")
        closest = d.get("closest")
        return cls(
            bool(d["ok"]),
            float(d["clearance"]),
            float("inf") if md is None else float(md),
            None if closest is None else tuple(int(x) for x in closest),  # type: ignore[arg-type]
            int(d["pairs"]),
            tuple(str(f) for f in d.get("failures", ())),
            str(d.get("method", "")),
        )


def _departures(timing: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(stop rows, their own departure times)``, s, the robot alone: the arrival at each stop
    row plus its weld dwell."""
    stops = np.flatnonzero(np.asarray(timing.stops))
    welds = set(np.asarray(timing.weld_rows).tolist())
    dwell = np.array([timing.weld_time if int(r) in welds else 0.0 for r in stops])
    return stops, np.asarray(timing.row_times)[stops] + dwell


def _stop_index(timing: Any, row: int, what: str) -> int:
    stops, _ = _departures(timing)
    hit = np.flatnonzero(stops == row)
    if not len(hit):
        raise PlanningError(f"interlock {what}: row {row} is not a stop row of its robot's route")
    return int(hit[0])


def _waits(timings: Sequence[Any], interlocks: Sequence[Interlock]) -> list[np.ndarray]:
    """Per robot, per stop row, the wait (s) before leaving it: the least waits that satisfy
    every interlock (a fixed point; waits only grow)."""
    deps = [_departures(t)[1] for t in timings]
    waits = [np.zeros(len(d)) for d in deps]
    idx = [
        (
            _stop_index(timings[i.first], i.release_row, i.name),
            _stop_index(timings[i.second], i.wait_row, i.name),
        )
        for i in interlocks
    ]
    for _ in range(len(interlocks) + 2):
        changed = False
        for lock, (a, b) in zip(interlocks, idx, strict=True):
            # ready: ``first`` at rest at release_row after its dwell, all its earlier waits in
            ready = deps[lock.first][a] + waits[lock.first][:a].sum()
            leave = deps[lock.second][b] + waits[lock.second][: b + 1].sum()
            if ready > leave + 1e-12:
                waits[lock.second][b] += ready - leave
                changed = True
        if not changed:
            return waits
    names = ", ".join(i.name for i in interlocks)
    raise PlanningError(f"the interlocks wait on each other in a circle (deadlock): {names}")


def station_schedule(
    names: Sequence[str],
    timings: Sequence[Any | None],
    interlocks: Sequence[Interlock] = (),
    weld_ids: Sequence[dict[int, str] | None] | None = None,
) -> StationSchedule:
    """The nominal schedule of robots running their timed routes under ``interlocks``.

    Parameters
    ----------
    names
        Robot names, station order.
    timings
        Per robot its :class:`~weldplan.robot.program.TimedTrajectory` (``None``: an idle robot).
    interlocks
        Each ties a stop row of one robot to a stop row of another (module docstring).
    weld_ids
        Per robot ``{timed row: weld id}`` to label its welds (optional).

    Raises
    ------
    PlanningError
        An interlock on an idle robot or a row that is not a stop row; a deadlock.
    """
    for lock in interlocks:
        if timings[lock.first] is None or timings[lock.second] is None:
            raise PlanningError(f"interlock {lock.name} names an idle robot")
    live = [k for k, t in enumerate(timings) if t is not None]
    waits_live = _waits([timings[k] for k in live], _renumber(interlocks, live))
    acts: list[Activity] = []
    for k, w in zip(live, waits_live, strict=True):
        ids = (weld_ids[k] if weld_ids is not None else None) or {}
        acts += _activities(k, timings[k], w, ids, interlocks)
    return StationSchedule(tuple(names), tuple(acts), tuple(interlocks))


def _renumber(interlocks: Sequence[Interlock], live: list[int]) -> list[Interlock]:
    pos = {k: n for n, k in enumerate(live)}
    return [
        Interlock(i.zone, pos[i.first], i.release_row, pos[i.second], i.wait_row, i.signal)
        for i in interlocks
    ]


def _activities(
    k: int, timing: Any, waits: np.ndarray, ids: dict[int, str], interlocks: Sequence[Interlock]
) -> list[Activity]:
    """Robot ``k``'s moves, welds and waits with its ``waits`` (s per stop row) put in."""
    stops, _ = _departures(timing)
    welds = set(np.asarray(timing.weld_rows).tolist())
    held = {i.wait_row: i.name for i in interlocks if i.second == k}
    rt = np.asarray(timing.row_times)
    out: list[Activity] = []
    shift = 0.0
    for n, r in enumerate(stops.tolist()):
        t = rt[r] + shift
        if n > 0:
            seg_start = out[-1].end if out else 0.0
            out.append(Activity(k, "move", seg_start, max(t, seg_start), r))
        if r in welds and timing.weld_time > 0:
            out.append(Activity(k, "weld", t, t + timing.weld_time, r, ids.get(r, "")))
            t += timing.weld_time
        if waits[n] > 0:
            out.append(Activity(k, "wait", t, t + waits[n], r, held.get(r, "")))
            t += waits[n]
            shift += waits[n]
    return out
