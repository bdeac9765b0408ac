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

A weld that no leg joins to home costs that weld, not the route (issue 27, item 3):
:func:`with_home` leaves out the first (the last) served weld whose lead (trail) leg fails, with
status ``collision`` and the cause in its detail, and tries the next one, at most
:data:`HOME_TRIES` welds at each end; a robot whose home joins none of them keeps no weld and
stands at home.

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

import dataclasses
import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.robot.placement.reach import COLLISION, OK

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
    lead, lead_zone = home_leg(det, home, first, "from home to the first")
    trail, trail_zone = home_leg(det, home, last, "between home and the last")
    # the way back is the leg from home reversed: the same motions, each checked both ways
    return HomeLegs(lead[:-1], lead_zone, trail[::-1][1:], trail_zone[::-1])


def home_leg(
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


#: welds tried at each end of a route for a leg from (or to) home before the rest are left out
#: (each try: a straight, a tucked move, then OMPL with the route's retries, about 10 CPU s a
#: run with the KR 150 and the spot gun: 8 tries at both ends took a two-robot demo station's
#: plan past 30 minutes; without the retries, the demo's weld 1 found no home leg)
HOME_TRIES = 4


def with_home(
    det: Any, rb: Any, path: Any, home: NDArray, welds: tuple[Any, list, list, tuple], stats: dict
) -> Any:
    """The joint route ``path`` (a frozen ``_JointPath`` of :mod:`weldplan.robot.route.plan`)
    starting and ending at ``home`` ``(6,)`` rad: the legs planned by ``det`` (``None``, no
    collision check: straight joint moves), their rows not exact and labelled with the route row
    they join. ``welds`` is ``(rows, status, detail, ids)``: the welds' route rows, and their
    status and detail lists, updated in place for the welds left out at either end (module
    docstring). The motions checked with the whole tool go to ``stats["whole_tool_motions"]``,
    the home and the welds left out to ``stats["home"]``."""
    q0 = check_home(rb, np.degrees(home), None if det is None else det.checker)
    rows, status, detail, ids = welds
    dropped: list[str] = []
    whole = list(stats.get("whole_tool_motions", []))
    if det is None:
        legs = HomeLegs(q0[None], np.zeros(1, bool), q0[None], np.zeros(1, bool))
    else:
        path, whole, legs = _legs_or_drop(det, q0, path, whole, welds, dropped)
    n = len(path.q)
    if not n:  # no weld left: the robot stands at home, every weld's row there
        stats["whole_tool_motions"] = []
        stats["home"] = _home_stats(q0, len(rows), 0, dropped)
        k = len(rows)
        return dataclasses.replace(
            path, q=np.repeat(q0[None], k, axis=0), row=np.asarray(rows, np.int64),
            exact=np.zeros(k, bool), branch=np.full(k, -1, np.int64), replanned=(),
        )  # fmt: skip
    ends = (int(path.row[0]), int(path.row[-1]))
    # every weld keeps a joint row labelled with its route row (the program's and the route
    # JSON's map): one cut off an end of the route stands at home, where the robot is
    kept = set(path.row.tolist())
    pre = [int(r) for r in rows if int(r) not in kept and int(r) < ends[0]]
    post = [int(r) for r in rows if int(r) not in kept and int(r) > ends[1]]
    a, b = len(pre) + len(legs.lead), len(legs.trail) + len(post)
    stats["whole_tool_motions"] = (
        [int(i) + len(pre) for i in np.flatnonzero(~legs.lead_zone)]
        + [int(i) + a for i in whole]
        + [int(i) + a + n - 1 for i in np.flatnonzero(~legs.trail_zone)]
    )
    stats["home"] = _home_stats(q0, a, b, dropped)
    row = [pre, np.full(len(legs.lead), ends[0]), path.row, np.full(len(legs.trail), ends[1]), post]
    q = [np.repeat(q0[None], len(pre), axis=0), legs.lead, path.q, legs.trail]
    return dataclasses.replace(
        path,
        q=np.vstack(q + [np.repeat(q0[None], len(post), axis=0)]),
        row=np.concatenate(row).astype(np.int64),
        exact=np.concatenate([np.zeros(a, bool), path.exact, np.zeros(b, bool)]),
        branch=np.concatenate([np.full(a, -1), path.branch, np.full(b, -1)]).astype(np.int64),
        replanned=tuple(int(i) for i in path.replanned),
    )


def _home_stats(q0: NDArray, a: int, b: int, dropped: list[str]) -> dict[str, Any]:
    """``stats["home"]``: the home (deg), the joint rows before and after the route's own, the
    welds left out for want of a home leg."""
    deg = [float(v) for v in np.degrees(q0)]
    return {"deg": deg, "lead_rows": a, "trail_rows": b, "left_out": dropped}


def _legs_or_drop(
    det: Any, q0: NDArray, path: Any, whole: list[int], welds: tuple, dropped: list[str]
) -> tuple[Any, list[int], HomeLegs]:
    """``(path, whole-tool motions, legs)``: the lead leg from home to the first served weld and
    the trail leg from the last one home; a served weld whose leg fails is left out (``welds``
    updated in place, its id appended to ``dropped``) and the path cut to the next one."""
    rows, status, detail, ids = welds
    served = [k for k in range(len(rows)) if status[k] == OK]
    at = {k: _exact_row(path, int(rows[k])) for k in served}
    lead = trail = None
    for end in ("lead", "trail"):
        tries = 0
        while served:
            k = served[0] if end == "lead" else served[-1]
            i = at[k]
            row = (path.q[i], int(rows[k]), int(path.branch[i]), True)
            words = f"{'from home to' if end == 'lead' else 'between home and'} weld {ids[k]}'s"
            try:
                got = home_leg(det, q0, row, words)
            except PlanningError as exc:
                got = None
                why = f"no home leg: {exc}"
            if got is not None:
                lead, trail = (got, trail) if end == "lead" else (lead, got)
                break
            tries += 1
            for j in served if tries >= HOME_TRIES else [k]:
                status[j] = COLLISION
                detail[j] = why if j == k else f"left out: no home leg at the route's {end}"
                dropped.append(str(ids[j]))
                log.info("weld %s left out: %s", ids[j], detail[j])
            served = [] if tries >= HOME_TRIES else [j for j in served if j != k]
    if not served:
        empty = (np.zeros((0, 6)), np.zeros(0, bool))
        return dataclasses.replace(path, q=np.zeros((0, 6))), [], HomeLegs(*empty, *empty)
    s, e = at[served[0]], at[served[-1]]
    cut = dataclasses.replace(
        path, q=path.q[s : e + 1], row=path.row[s : e + 1], exact=path.exact[s : e + 1],
        branch=path.branch[s : e + 1],
    )  # fmt: skip
    whole = [i - s for i in whole if s <= i < e]
    (lq, lz), (tq, tz) = lead, trail
    # the way back is the leg from home reversed: the same motions, each checked both ways
    return cut, whole, HomeLegs(lq[:-1], lz, tq[::-1][1:], tz[::-1])


def _exact_row(path: Any, r: int) -> int:
    """The exact joint row of route row ``r`` in ``path``."""
    on = np.flatnonzero((path.row == r) & path.exact)
    return int(on[0])
