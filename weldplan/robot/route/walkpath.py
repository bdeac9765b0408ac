"""The joint path the robot's walk (:mod:`weldplan.robot.route.walk`) assembles: its rows, and
the rows of a detour and of the route's tail added to it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.robot.model.arm import Robot
from weldplan.robot.route.legtrial import leg_hits
from weldplan.robot.route.replan import Detour

log = logging.getLogger(__name__)


@dataclass
class JointPath:
    """A joint route being assembled: rows and, per row, the zone flag of the motion leaving it."""

    q: list[NDArray[np.float64]] = field(default_factory=list)
    row: list[int] = field(default_factory=list)
    exact: list[bool] = field(default_factory=list)
    branch: list[int] = field(default_factory=list)
    zone: list[bool] = field(default_factory=list)

    #: the per-row lists, in order
    LISTS = ("q", "row", "exact", "branch", "zone")

    def add(self, q: NDArray, row: int, exact: bool, branch: int, zone: bool = True) -> None:
        self.q.append(np.asarray(q, dtype=np.float64))
        self.row.append(int(row))
        self.exact.append(bool(exact))
        self.branch.append(int(branch))
        self.zone.append(bool(zone))

    def mark(self) -> tuple[int, bool]:
        """Where the path ends now (:meth:`cut` returns to it)."""
        return len(self.q), bool(self.zone[-1]) if self.zone else True

    def cut(self, mark: tuple[int, bool]) -> tuple[Any, ...]:
        """Remove every row after ``mark`` and return them (:meth:`paste` puts them back)."""
        n, z = mark
        saved = tuple(getattr(self, k)[n:] for k in self.LISTS) + (self.zone[n - 1] if n else True,)
        for k in self.LISTS:
            del getattr(self, k)[n:]
        if n:
            self.zone[n - 1] = z
        return saved

    def paste(self, saved: tuple[Any, ...]) -> None:
        """Put back what :meth:`cut` removed (the path must end where it did then)."""
        *lists, z = saved
        if self.zone:
            self.zone[-1] = z
        for k, v in zip(self.LISTS, lists, strict=True):
            getattr(self, k).extend(v)

    def arrays(self) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray]:
        """``q (k, 6)``, ``row (k,)``, ``exact (k,)``, ``branch (k,)``, ``zone (k - 1,)``."""
        return (
            np.array(self.q).reshape(-1, 6),
            np.array(self.row, dtype=np.int64),
            np.array(self.exact, dtype=bool),
            np.array(self.branch, dtype=np.int64),
            np.array(self.zone[:-1], dtype=bool),
        )


def subdivide(P: NDArray[np.float64], inner: int) -> NDArray[np.float64]:
    """``P (p, 6)`` with points added on its longest segments (halving them) until it has at
    least ``inner`` rows strictly between its ends; the polyline itself is unchanged."""
    P = np.asarray(P, dtype=np.float64)
    while len(P) - 2 < inner:
        seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
        i = int(np.argmax(seg))
        P = np.insert(P, i + 1, (P[i] + P[i + 1]) / 2, axis=0)
    return P


def add_detour(
    out: JointPath,
    robot: Robot,
    path: NDArray,
    ia: int,
    ib: int,
    rows: NDArray[np.int64],
    q: NDArray,
    branch: NDArray,
    leave_zone: bool = True,
) -> None:
    """Rows of a detour from the weld at route row ``ia`` to the one at ``ib``: the retract
    (labelled ``ia``), inner points (labelled ``ia``, then one per weld passed between), the
    approach (labelled ``ib``) and the weld ``ib`` itself. ``leave_zone``: the motion from the
    path's end to ``path[0]`` is checked with the contact zone exempt (it leaves a weld; not so
    from a clear configuration, :meth:`weldplan.robot.route.walk._Walk.retrace`)."""
    passed = [int(r) for r in rows if ia < r < ib]
    P = subdivide(path, len(passed))
    pb = robot.branch_of(P)
    labels = [ia] * len(P)
    labels[-1] = ib
    for j, r in enumerate(passed):  # the last inner points stand for the welds passed
        labels[len(P) - 1 - len(passed) + j] = r
    out.zone[-1] = leave_zone  # weld -> retract: contact zone exempt
    for p, lab, b in zip(P, labels, pb, strict=True):
        out.add(p, lab, False, int(b), zone=False)
    out.zone[-1] = True  # approach -> weld
    out.add(q[ib], ib, True, int(branch[ib]))


def tail(
    det: Detour,
    out: JointPath,
    q: NDArray,
    ex: NDArray,
    branch: NDArray,
    ia: int,
    own: NDArray[np.bool_],
    blocked: set[int] | None = None,
) -> None:
    """The route's rows after the last served weld (module docstring); ``own[i]``: the contact
    zone is exempt on the route's own motion leaving row ``i``."""
    m = len(q)
    if ia + 1 >= m:
        return
    if not leg_hits(det, q, own, ia, m - 1, blocked):
        out.zone[-1] = bool(own[ia])
        for i in range(ia + 1, m):
            out.add(q[i], i, bool(ex[i]), int(branch[i]), bool(own[i]))
        return
    got = det.retract(q[ia], det.T_tcp[ia], int(branch[ia]))
    out.zone[-1] = True  # weld -> retract (or no motion): contact zone exempt, as checked
    if got is None:
        # no way off the last served weld: the robot stays there (zero motions), the route's
        # later welds are passed without welding; before, the route's own blocked rows were
        # kept and the final check refused the whole route
        log.info("no retract from the last served weld: the program ends there")
        for i in range(ia + 1, m):
            out.add(q[ia], i, False, int(branch[ia]))
        return
    # the rest of the route's rows as points on the retract from the last served weld (a motion
    # retract() checked), the last of them the retract configuration itself
    P = subdivide(np.vstack([q[ia], got[0]]), m - 2 - ia)[1:]
    pb = det.robot.branch_of(P)
    for j, i in enumerate(range(ia + 1, m)):
        out.add(P[j], i, False, int(pb[j]))
