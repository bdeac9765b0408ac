"""The robot's home: where its route starts and ends (KUKA's ``PTP HOME``, ABB's home target).

A station engineer starts every robot program at a known configuration away from the part and
ends it there, so that the cell starts and stops in a known state and, with several robots, a
robot can wait at home behind an interlock while another works (issue 30, item 4). With a
``home`` (:attr:`weldplan.robot.settings.JointRouteSettings.home`), :func:`with_home` adds two
legs to the assembled joint route, planned like any detour of :mod:`weldplan.robot.route.replan`:

* *home -> first row*: from the home configuration to the first weld's approach: the weld left
  along one of the gun's proven exits or a retract (:meth:`~weldplan.robot.route.Detour.leave`),
  reversed, so the last motion lowers the gun onto the weld with its contact zone exempt; the
  transfer from home to the start of that approach straight in joint space when free, else
  through a tucked arm, else OMPL (:meth:`~weldplan.robot.route.Detour.transfer`: the whole
  tool and every link checked against the part, the floor and the robot itself);
* *last row -> home*: the same, leaving the last weld.

The new rows are not exact (no route pose): they carry the route row of the weld they join
(the first or the last), as the rows of a re-planned leg do, so the program, the route JSON and
``weldplan verify`` treat them as the joint moves they are. :func:`check_home` refuses a home
that is not a configuration of the robot: the wrong number of values, outside the joint limits,
or touching the part, the floor or the robot itself.

The default home of a robot of several (:mod:`weldplan.multi.station`) is
:data:`CONVENTIONAL_HOME_DEG`, the KUKA arms' conventional ``HOME`` (``$H_POS``): A1 0, A2 -90
(upper arm upright), A3 90 (forearm level), wrist straight.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError

log = logging.getLogger(__name__)

#: deg, A1..A6: the conventional home of a six-axis KUKA arm (the controller's ``$H_POS``,
#: ``XHOME``): the upper arm upright, the forearm level, the wrist straight
CONVENTIONAL_HOME_DEG = (0.0, -90.0, 90.0, 0.0, 0.0, 0.0)


def check_home(robot: Any, home_deg: ArrayLike, checker: Any = None) -> NDArray[np.float64]:
    """``(6,)`` rad: the home ``home_deg`` (deg, one value per axis) of ``robot`` (a
    :class:`~weldplan.robot.model.Robot` at its base), refused with a
    :class:`~weldplan.errors.ConfigError` (field ``home``) when it has the wrong length, is
    outside the joint limits, or, with a ``checker``
    (:class:`~weldplan.robot.collision.RobotCollision`, the whole tool), touches the part, the
    floor or the robot itself (the body or pair named)."""
    h = np.asarray(home_deg, dtype=np.float64).reshape(-1)
    n = len(robot.joint_names)
    if len(h) != n or not np.all(np.isfinite(h)):
        raise ConfigError(f"home needs {n} finite joint values (deg), got {len(h)}", field="home")
    q = np.radians(h)
    lo, hi = robot.lower, robot.upper
    out = np.flatnonzero((q < lo) | (q > hi))
    if len(out):
        j = int(out[0])
        raise ConfigError(
            f"home A{j + 1} = {h[j]:g} deg is outside the joint's limits "
            f"[{np.degrees(lo[j]):g}, {np.degrees(hi[j]):g}] deg",
            field="home",
        )
    if checker is not None:
        hit = checker.states_blocked(q[None], zone=False)[0]
        if hit is not None:
            what = hit.replace("/", " touches ") if "/" in hit else f"{hit} touches the part"
            raise ConfigError(
                f"the robot at home {[round(float(v), 3) for v in h]} deg collides: {what}",
                field="home",
            )
    return q


@dataclass(frozen=True)
class HomeLegs:
    """The two legs :func:`with_home` adds.

    Attributes
    ----------
    lead
        ``(p, 6)`` rad: home (the first row) and the rows after it, up to the route's first row
        (not included).
    lead_zone
        ``(p,) bool``: per motion from a ``lead`` row to the next row (the last one to the
        route's first row), whether the tool's contact zone is exempt (only the motion that
        lowers the gun onto the weld).
    trail
        ``(r, 6)`` rad: the rows after the route's last row, home the last.
    trail_zone
        ``(r,) bool``: per motion into a ``trail`` row, the same.
    """

    lead: NDArray[np.float64]
    lead_zone: NDArray[np.bool_]
    trail: NDArray[np.float64]
    trail_zone: NDArray[np.bool_]


def home_legs(
    det: Any, home: NDArray[np.float64], first: tuple[NDArray, int, int, bool],
    last: tuple[NDArray, int, int, bool],
) -> HomeLegs:  # fmt: skip
    """The legs home -> ``first`` and ``last`` -> home (module docstring).

    Parameters
    ----------
    det
        The route's :class:`~weldplan.robot.route.Detour` (its checker, exits, OMPL budget and
        seed).
    home
        ``(6,)`` rad.
    first, last
        ``(q (6,) rad, route row, IK branch, exact)`` of the route's first and last joint rows:
        an exact row (a weld) is left along its exit or retract, another joined directly.

    Raises
    ------
    PlanningError
        No leg: neither a straight, a tucked nor an OMPL transfer joins home to the row.
    """
    lead, lead_zone = _leg(det, home, first, "from home to the first")
    trail, trail_zone = _leg(det, home, last, "between home and the last")
    # the way back is the leg from home reversed: the same motions, each checked both ways
    return HomeLegs(lead[:-1], lead_zone, trail[::-1][1:], trail_zone[::-1])


def _leg(
    det: Any, home: NDArray[np.float64], end: tuple[NDArray, int, int, bool], words: str
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """``(rows (p + 1, 6) rad from home to the route's row, both included; zone (p,) bool per
    motion)``: the transfer from home to the clear end of the row's exit (or to the row itself
    when it is not exact or has none), then the exit reversed."""
    q, row, branch, exact = end
    q = np.asarray(q, dtype=np.float64)
    out = det.leave(q, row, branch) if exact else None
    clear = q if out is None else np.asarray(out)[-1]
    path = det.transfer(np.asarray(home, dtype=np.float64), clear)
    if path is None:
        raise PlanningError(
            f"no collision-free motion {words} joint row (route row {row}): neither straight, "
            "through a tucked arm nor by OMPL"
        )
    path = np.asarray(path, dtype=np.float64)
    if out is None:
        return path, np.zeros(len(path) - 1, dtype=bool)
    back = np.asarray(out)[::-1][1:]  # the exit reversed, its clear end already on the path
    rows = np.vstack([path, back, q[None]])
    zone = np.zeros(len(rows) - 1, dtype=bool)
    zone[-1] = True  # lowering the gun onto the weld: its contact zone exempt, as leaving it
    return rows, zone
