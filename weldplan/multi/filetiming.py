"""A several-robot station's trajectory CSVs read back on the schedule's clock: what the
re-check (:mod:`weldplan.multi.recheck`), the program signals check and the station page
rebuilt from saved files (:func:`weldplan.viz.station_page.saved_station_robots`) read of each
robot's timed route.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError

#: s: the schedule (6 decimals) against a trajectory CSV's ``t`` (4 decimals)
CYCLE_TOL = 1e-3


def _trajectory_end(path: Any) -> float:
    """s: the last ``t`` of a trajectory CSV (``#`` lines skipped)."""
    return float(_trajectory_rows(path)[-1][0])


def _trajectory_rows(path: Any) -> list[list[str]]:
    """A trajectory CSV's rows, its header first (``#`` lines skipped)."""
    try:
        lines = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")]
    except OSError as exc:
        raise InputError(f"cannot read it: {exc.strerror}", path=path) from None
    rows = list(csv.reader(lines))
    if len(rows) < 2 or rows[0][:1] != ["t"]:
        raise InputError("not a trajectory CSV (no t column or no row)", path=path)
    return rows


@dataclass(frozen=True, eq=False)
class FileTiming:
    """A robot's timed route as the saved files give it: what the replay reads of a
    :class:`~weldplan.robot.program.TimedTrajectory`.

    Attributes
    ----------
    t, q
        ``(m,)`` s and ``(m, 6)`` rad: the trajectory CSV's samples.
    stops
        ``(n,) bool``: the timed rows where the robot rests (the schedule's: row 0 and the
        rows its moves end at).
    row_times
        ``(n,)`` s: the arrival at each stop row on the robot's own clock (its moves and welds
        before it, its waits taken out); 0 at the other rows.
    """

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    stops: NDArray[np.bool_]
    row_times: NDArray[np.float64]


def file_timing(schedule: Any, k: int, trajectory: Any) -> FileTiming:
    """Robot ``k``'s :class:`FileTiming` from ``schedule`` and its ``trajectory`` CSV.

    Raises :class:`~weldplan.errors.InputError` naming the CSV when it is not a trajectory or
    an arrival falls on none of its samples."""
    rows = _trajectory_rows(trajectory)
    t = np.array([float(r[0]) for r in rows[1:]])
    q = np.array([[float(v) for v in r[2:]] for r in rows[1:]])
    own, arrive = 0.0, {0: 0.0}
    for a in schedule.of(k):
        if a.kind != "wait":
            own += a.duration
        if a.kind == "move":
            arrive.setdefault(a.row, own)
    n = max(arrive) + 1
    stops, times = np.zeros(n, bool), np.zeros(n)
    for r, at in arrive.items():
        stops[r], times[r] = True, at
        if np.min(np.abs(t - at)) > CYCLE_TOL:
            raise InputError(f"no sample at {at:.4f} s, robot {k + 1}'s arrival at row {r}",
                             path=trajectory)  # fmt: skip
    return FileTiming(t, q, stops, times)
