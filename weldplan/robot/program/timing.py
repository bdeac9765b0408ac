"""Cycle time of a joint-space route: time-optimal parameterisation with toppra, weld dwell.

The route reaches the robot as one joint vector per waypoint (``q (n, 6)`` rad, the robot
engineer's :class:`~weldplan.robot.route.RobotRoute`). The robot comes to rest at every *stop*
row: each weld spot (it welds there) and each via point the program writes as an exact stop
(``fine`` in RAPID, no ``C_DIS`` in KRL: the corner's free margin allowed no blend,
:mod:`weldplan.io.blending`). Between two consecutive stops the motion is one rest-to-rest
segment, time-parameterised by TOPP-RA (Pham & Pham, "A new approach to time-optimal path
parameterization based on reachability analysis", IEEE T-RO 34(3), 2018; the ``toppra``
package) under the joint velocity limits (URDF) and acceleration limits (:class:`Robot`,
scaled by the options).

The geometric path of a segment
-------------------------------
TOPP-RA needs a twice-differentiable path. A cubic spline straight through the waypoints
would round every corner by an amount the route never checked, so the path is the cubic spline
(``toppra.SplineInterpolator``, not-a-knot) through the waypoints *and* knots inserted on the
joint-space segments between them, at most ``h`` apart: it reproduces straight segments exactly
and rounds every corner only within a fraction of ``h``. ``h`` shrinks (by the ratio of the
tolerance to the deviation, at least by half), from the longest interval, until the largest
per-joint
deviation of the spline from the waypoints' joint-space polyline, at the same path parameter
(``s`` = joint-space arc length, a bound on the geometric deviation), is at most
``tolerance`` rad (:data:`DEFAULT_TOLERANCE_RAD`). The deviation reached is reported per
segment; the dense samples (:attr:`TimedTrajectory.q`) are the path to re-check for collision.

Deviations from the paper, named: the parameterisation is TOPP-RA's with toppra's constant
acceleration parametriser (``ParametrizeConstAccel``) on a grid that contains every waypoint,
so the arrival time at each waypoint is exact on that grid; constraints hold at the grid points
(TOPP-RA's interpolation discretisation), not in between, so a sampled velocity can exceed its
limit by the discretisation error (tests bound it). The grid follows toppra's own refinement rule
(:data:`GRID_ERROR_RAD`); its error makes the time conservative: on a random joint walk with a
sharp corner at every row (tests' route, seed 1) 3.54 s at the default against 3.49 s with a
grid ten times finer; on a 1000-row, 200-weld walk 307.1 s against 301.8 s (+1.8 %), for
15 s instead of 24 s of computing on a loaded 2-core machine.

Constant TCP speed (the comparison the issue asks for): :func:`constant_speed_time` is the same
route's Cartesian polyline length divided by one TCP speed, plus the same weld dwell: what a
program with one ``v``-speed on every move would take if the robot had no acceleration limits.
"""

from __future__ import annotations

import importlib
import logging
import math
import sys
import types
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.geometry.pathcore import polyline_length

log = logging.getLogger(__name__)

#: largest deviation (rad, any joint) of the timed spline from the waypoints' joint polyline;
#: 5e-4 rad is 1.5 mm at the 3.1 m reach of the KR 150 R3100-2
DEFAULT_TOLERANCE_RAD = 5e-4
#: sampling period (s) of :attr:`TimedTrajectory.t`: 100 Hz, finer than a KUKA KRC's 12 ms
#: interpolation cycle; every waypoint arrival is a sample as well
DEFAULT_DT = 0.01
#: a regular sample closer than ``MIN_GAP_DT * dt`` to a waypoint arrival is dropped (the
#: arrival is the exact row): two samples never share a time, and the trajectory CSV's
#: ``t`` (0.1 ms resolution) strictly increases for any ``dt`` >= 1 ms
MIN_GAP_DT = 0.1
#: the most times the knot spacing ``h`` shrinks (at least halving) before giving up
MAX_DOUBLINGS = 10
#: TOPP-RA's grid: toppra's own refinement rule (``propose_gridpoints``), an interval is split
#: while ``0.5 max|q''(s)| ds^2`` exceeds GRID_ERROR_RAD or ds exceeds GRID_MAX_DS (rad of
#: joint-space arc length); at least MIN_GRID points
GRID_ERROR_RAD = 1e-4
GRID_MAX_DS = 0.05
MIN_GRID = 100
#: constant TCP speed (mm/s) of the comparison when none is given: a typical air-move speed of a
#: spot-welding program
DEFAULT_TCP_SPEED = 1000.0


@dataclass(frozen=True)
class Segment:
    """One rest-to-rest motion between two stop rows.

    Attributes
    ----------
    start, end
        Route rows (``start < end``) where the robot is at rest.
    duration
        s, motion only (the weld dwell is not in it).
    deviation
        rad: largest per-joint distance of the timed path from the joint polyline.
    inserted
        Knots inserted between the waypoints to reach the tolerance.
    """

    start: int
    end: int
    duration: float
    deviation: float
    inserted: int


@dataclass(frozen=True, eq=False)
class TimedTrajectory:
    """The timed route: arrival time per waypoint, segments, dense samples.

    Attributes
    ----------
    joint_names
        ``(6,)`` names as in the URDF (the CSV's columns).
    row_times
        ``(n,) float`` s: when the robot reaches each route row (at a weld: before the dwell).
    stops
        ``(n,) bool``: rows where the robot is at rest.
    weld_rows
        ``(w,) int``: the rows with a weld dwell.
    weld_time
        s per weld spot.
    segments
        The rest-to-rest motions, in order.
    t, step, q
        Samples: ``(m,)`` s, ``(m,)`` int, ``(m, 6)`` rad. ``step`` is the route row the robot is
        moving to, or resting at (during a weld dwell, the weld's row).
    """

    joint_names: tuple[str, ...]
    row_times: NDArray[np.float64]
    stops: NDArray[np.bool_]
    weld_rows: NDArray[np.int64]
    weld_time: float
    segments: tuple[Segment, ...]
    t: NDArray[np.float64]
    step: NDArray[np.int64]
    q: NDArray[np.float64]

    @property
    def total(self) -> float:
        """Cycle time (s): every motion plus every weld dwell."""
        return float(self.t[-1]) if len(self.t) else 0.0

    @property
    def motion_time(self) -> float:
        """s in motion (the cycle time less the dwell)."""
        return float(sum(s.duration for s in self.segments))

    @property
    def deviation(self) -> float:
        """rad: the largest deviation of any segment (0 for a route without motion)."""
        return max((s.deviation for s in self.segments), default=0.0)

    def leg_times(self) -> NDArray[np.float64]:
        """``(w - 1,)`` s from the end of one weld's dwell to the end of the next one's."""
        w = self.weld_rows
        arrive = self.row_times[w]
        return np.diff(arrive + self.weld_time) if len(w) > 1 else np.zeros(0)


def check_limits(velocity: ArrayLike, acceleration: ArrayLike) -> tuple[NDArray, NDArray]:
    """``(d,)`` velocity (rad/s) and acceleration (rad/s^2) limits, each finite and > 0.

    Raises :class:`ConfigError` naming the field (``velocity`` / ``acceleration``) otherwise.
    """
    out = []
    for name, v in (("velocity", velocity), ("acceleration", acceleration)):
        a = np.asarray(v, dtype=np.float64).reshape(-1)
        if len(a) == 0 or not np.all(np.isfinite(a)) or np.any(a <= 0):
            raise ConfigError(f"joint {name} limits must be finite and > 0, got {a}", field=name)
        out.append(a)
    if len(out[0]) != len(out[1]):
        raise ConfigError("velocity and acceleration limits differ in length", field="acceleration")
    return out[0], out[1]


def check_weld_time(value: float) -> float:
    """``value`` s as a finite number >= 0, else :class:`ConfigError` (field ``weld_time``)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and v >= 0):
        raise ConfigError(
            f"weld time must be a finite number of s >= 0, got {value!r}", field="weld_time"
        )
    return v


class _DeferredModule(types.ModuleType):
    """Stands for a module not imported yet: its first attribute asked imports the module
    (:func:`importlib.import_module`) and answers from it."""

    def __getattr__(self, name: str) -> Any:
        if sys.modules.get(self.__name__) is self:  # still standing in: not importable yet
            raise AttributeError(name)
        return getattr(importlib.import_module(self.__name__), name)


def _toppra() -> Any:
    """The ``toppra`` package, imported without loading ``matplotlib.pyplot``.

    ``toppra.algorithm.algorithm`` imports pyplot at its top for its plotting helpers (about
    0.45 s, most of toppra's import), which timing never calls. While toppra is imported, a
    :class:`_DeferredModule` stands in ``sys.modules`` for pyplot, and is taken out at once:
    toppra's ``plt`` imports the real pyplot on its first use, and anyone else's ``import
    matplotlib.pyplot`` is the ordinary one.
    """
    name = "matplotlib.pyplot"
    if "toppra.algorithm" in sys.modules or name in sys.modules:
        import toppra

        return toppra
    stand_in = _DeferredModule(name)
    sys.modules[name] = stand_in
    try:
        import toppra
        import toppra.algorithm  # noqa: F401  (the module whose import wants pyplot)
    finally:
        if sys.modules.get(name) is stand_in:
            del sys.modules[name]
    return toppra


def _spline_path(q: NDArray[np.float64], tolerance: float):
    """The spline through ``q (k, d)`` within ``tolerance`` of its polyline (module docstring).

    Returns ``(path, s_waypoints (k,), deviation, inserted)``.
    """
    ta = _toppra()
    seg = np.linalg.norm(np.diff(q, axis=0), axis=1)
    s_way = np.concatenate([[0.0], np.cumsum(seg)])
    if len(q) == 2:  # a straight segment: the spline through two points is the line itself
        return ta.SplineInterpolator(s_way, q), s_way, 0.0, 0
    h = float(seg.max())
    for _ in range(MAX_DOUBLINGS + 1):
        # every interval cut into pieces of at most h (rad of joint-space arc length)
        pieces = np.maximum(np.ceil(seg / h - 1e-9), 1).astype(np.int64)
        frac = np.concatenate([np.arange(p) / p for p in pieces])
        start = np.repeat(s_way[:-1], pieces) + frac * np.repeat(seg, pieces)
        s_knots = np.concatenate([start, s_way[-1:]])
        knots = np.column_stack([np.interp(s_knots, s_way, q[:, j]) for j in range(q.shape[1])])
        path = ta.SplineInterpolator(s_knots, knots)
        s_chk = (s_knots[:-1, None] + np.diff(s_knots)[:, None] * (np.arange(8) / 8.0)).ravel()
        lin = np.column_stack([np.interp(s_chk, s_way, q[:, j]) for j in range(q.shape[1])])
        dev = float(np.max(np.abs(path(s_chk) - lin)))
        if dev <= tolerance:
            return path, s_way, dev, int(len(s_knots) - len(q))
        # the corner error shrinks about linearly with h: aim a little below the tolerance
        h *= min(0.5, max(0.05, 0.8 * tolerance / dev))
    raise PlanningError(
        f"the joint spline stays {dev:.2g} rad off its polyline with knots every {2 * h:.2g} rad "
        f"(tolerance {tolerance:g} rad)"
    )


def _gridpoints(path: Any, s_way: NDArray[np.float64]) -> NDArray[np.float64]:
    """TOPP-RA grid over ``[0, s_way[-1]]`` containing every waypoint: toppra's
    ``propose_gridpoints`` rule (:data:`GRID_ERROR_RAD`, :data:`GRID_MAX_DS`), vectorised per
    spline piece (``q''`` is linear on a cubic piece, so its largest value is at an end)."""
    knots = np.asarray(path.ss_waypoints, dtype=np.float64)
    dd = np.abs(np.asarray(path(knots, 2), dtype=np.float64)).max(axis=1)  # (m,)
    curv = np.maximum(dd[:-1], dd[1:])
    ds = np.diff(knots)
    n = np.ceil(np.maximum(ds * np.sqrt(0.5 * curv / GRID_ERROR_RAD), ds / GRID_MAX_DS) - 1e-9)
    n = np.maximum(n, 1).astype(np.int64)
    if n.sum() < MIN_GRID:
        n = np.maximum(n, int(np.ceil(MIN_GRID / len(n))))
    frac = np.concatenate([np.arange(k) / k for k in n])
    grid = np.repeat(knots[:-1], n) + frac * np.repeat(ds, n)
    return np.unique(np.concatenate([grid, knots[-1:], s_way]))


#: toppra's constraints per pair of limits (:func:`_limits`)
_LIMITS: dict[tuple[bytes, bytes], tuple[Any, Any]] = {}


def _limits(velocity: NDArray, acceleration: NDArray) -> list[Any]:
    """toppra's joint velocity and acceleration constraints of these limits ``(d,)`` (rad/s,
    rad/s^2), built once per pair of limits: they hold no state of a path (toppra asks them per
    path and grid), and a route's hundred segments built the same two, with their checks and
    format strings, a hundred times."""
    v = np.asarray(velocity, dtype=np.float64)
    a = np.asarray(acceleration, dtype=np.float64)
    key = (v.tobytes() + bytes(str(v.shape), "ascii"), a.tobytes() + bytes(str(a.shape), "ascii"))
    got = _LIMITS.get(key)
    if got is None:
        constraint = _toppra().constraint
        got = (
            constraint.JointVelocityConstraint(v),
            constraint.JointAccelerationConstraint(
                np.column_stack([-a, a]),
                discretization_scheme=constraint.DiscretizationType.Interpolation,
            ),
        )
        if len(_LIMITS) >= 16:
            _LIMITS.clear()
        _LIMITS[key] = got
    return list(got)


def _time_segment(
    q: NDArray[np.float64], velocity: NDArray, acceleration: NDArray, tolerance: float
):
    """Rest-to-rest TOPP-RA over ``q (k, d)``: ``(at, arrival times (k,), deviation,
    inserted)``; ``at(t (m,)) -> (m, d)`` joint values at times ``t`` s."""
    ta = _toppra()
    algo = ta.algorithm
    ParameterizationReturnCode = ta.algorithm.algorithm.ParameterizationReturnCode

    path, s_way, dev, inserted = _spline_path(q, tolerance)
    grid = _gridpoints(path, s_way)
    cons = _limits(velocity, acceleration)
    inst = algo.TOPPRA(cons, path, gridpoints=grid, parametrizer="ParametrizeConstAccel")
    inst.compute_parameterization(0.0, 0.0)
    data = inst.problem_data
    if data.return_code != ParameterizationReturnCode.Ok or data.sd_vec is None:
        raise PlanningError(f"toppra could not time a segment ({data.return_code})")
    sd = np.asarray(data.sd_vec, dtype=np.float64)
    # ParametrizeConstAccel's law, vectorised: constant path acceleration u_i on each grid
    # interval, t_{i+1} = t_i + 2 (s_{i+1} - s_i) / (sd_i + sd_{i+1})
    ds = np.diff(grid)
    with np.errstate(divide="ignore"):
        t_grid = np.concatenate([[0.0], np.cumsum(2.0 * ds / (sd[:-1] + sd[1:]))])
    u = (sd[1:] ** 2 - sd[:-1] ** 2) / (2.0 * ds)

    def at(times: NDArray[np.float64]) -> NDArray[np.float64]:
        i = np.clip(np.searchsorted(t_grid, times, side="right") - 1, 0, len(ds) - 1)
        dt = times - t_grid[i]
        s = grid[i] + sd[i] * dt + 0.5 * u[i] * dt * dt
        return np.asarray(path(np.clip(s, 0.0, grid[-1])), dtype=np.float64)

    arrive = t_grid[np.searchsorted(grid, s_way)]
    return at, arrive, dev, inserted


def time_route(
    q: ArrayLike,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    *,
    weld_rows: ArrayLike,
    stops: ArrayLike | None = None,
    weld_time: float = 0.0,
    tolerance: float = DEFAULT_TOLERANCE_RAD,
    dt: float = DEFAULT_DT,
    joint_names: tuple[str, ...] | None = None,
) -> TimedTrajectory:
    """Time the joint-space route ``q`` (module docstring).

    Parameters
    ----------
    q
        ``(n, d)`` rad, one joint vector per route waypoint (travel order).
    velocity, acceleration
        ``(d,)`` limits, rad/s and rad/s^2 (already scaled).
    weld_rows
        Rows of the weld spots: the robot rests there for ``weld_time`` s.
    stops
        ``(n,) bool``: further rows where the robot comes to rest (exact stops); the first and last
        rows and every weld row are stops whatever it says.
    tolerance
        rad: largest deviation of the timed path from the joint polyline.
    dt
        s between samples.
    joint_names
        Column names (default ``j1..jd``).

    Raises
    ------
    ConfigError
        Limits not finite and positive, a weld time NaN or negative, a ``q`` with NaN.
    PlanningError
        toppra fails on a segment.
    """
    q, vel, acc, wt = _check_route_args(q, velocity, acceleration, weld_time, tolerance, dt)
    n, d = q.shape
    welds = np.asarray(weld_rows, dtype=np.int64).reshape(-1)
    stop = np.zeros(n, bool) if stops is None else np.asarray(stops, dtype=bool).copy()
    stop[welds] = True
    stop[[0, -1]] = True
    names = tuple(joint_names) if joint_names is not None else tuple(f"j{i + 1}" for i in range(d))

    row_t = np.zeros(n)
    ts, steps, qs = [np.zeros(1)], [np.zeros(1, np.int64)], [q[:1]]
    segments: list[Segment] = []
    now = 0.0
    dwell = set(welds.tolist())
    stop_rows = np.flatnonzero(stop)
    for a, b in zip(stop_rows[:-1], stop_rows[1:], strict=True):
        if a in dwell and wt > 0:  # the weld at ``a``, before leaving it
            now += wt
            ts.append(np.array([now]))
            steps.append(np.array([a]))
            qs.append(q[a : a + 1])
        sampled = _sample_segment(q, int(a), int(b), vel, acc, tolerance, dt)
        if sampled is None:  # the robot does not move between the two stops
            row_t[a + 1 : b + 1] = now
            segments.append(Segment(int(a), int(b), 0.0, 0.0, 0))
            continue
        arrive_rows, grid_t, grid_steps, grid_q, seg = sampled
        row_t[a + 1 : b + 1] = now + arrive_rows
        ts.append(now + grid_t)
        steps.append(grid_steps)
        qs.append(grid_q)
        now += seg.duration
        segments.append(seg)
    last = int(stop_rows[-1])
    if last in dwell and wt > 0:
        now += wt
        ts.append(np.array([now]))
        steps.append(np.array([last]))
        qs.append(q[last : last + 1])
    out_t = np.concatenate(ts)
    out_q = np.concatenate(qs)
    for a in (row_t, out_t, out_q):
        a.setflags(write=False)
    log.info(
        "timed %d rows: %d segments, %.3f s (%.2g rad deviation)",
        n,
        len(segments),
        now,
        max((s.deviation for s in segments), default=0.0),
    )
    return TimedTrajectory(
        names, row_t, stop, welds, wt, tuple(segments), out_t, np.concatenate(steps), out_q
    )


def _check_route_args(
    q: ArrayLike,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    weld_time: float,
    tolerance: float,
    dt: float,
) -> tuple[NDArray[np.float64], NDArray, NDArray, float]:
    """:func:`time_route`'s arguments checked: ``(q (n, d), velocity (d,), acceleration (d,),
    weld time)``; ConfigError on anything not finite and positive (``q``: not finite)."""
    q = np.asarray(q, dtype=np.float64)
    if q.ndim != 2 or len(q) == 0 or not np.all(np.isfinite(q)):
        raise ConfigError("q must be a finite (n, d) array of joint values", field="q")
    vel, acc = check_limits(velocity, acceleration)
    if len(vel) != q.shape[1]:
        raise ConfigError(f"{len(vel)} joint limits for {q.shape[1]} joints", field="velocity")
    wt = check_weld_time(weld_time)
    if not (math.isfinite(tolerance) and tolerance > 0 and math.isfinite(dt) and dt > 0):
        raise ConfigError("tolerance and dt must be finite and > 0", field="tolerance")
    return q, vel, acc, wt


def _sample_segment(
    q: NDArray[np.float64],
    a: int,
    b: int,
    velocity: NDArray,
    acceleration: NDArray,
    tolerance: float,
    dt: float,
) -> tuple[NDArray, NDArray, NDArray, NDArray, Segment] | None:
    """The rest-to-rest segment from stop row ``a`` to stop row ``b`` of ``q (n, d)``, timed
    and sampled every ``dt`` s; None when the robot does not move between them.

    Rows equal to the row before them are dropped before timing (they arrive with it).

    Returns
    -------
    arrive_rows, t, steps, q, segment
        ``(b - a,)`` s arrival time of rows ``a + 1 .. b`` after leaving ``a``; ``(m,)`` s
        sample times after leaving ``a`` (every ``dt`` and every arrival, the last = the
        duration); ``(m,)`` the row each sample is on its way from; ``(m, d)`` rad the
        samples, the last exactly ``q[b]``; the :class:`Segment`.
    """
    d = q.shape[1]
    seg_q = q[a : b + 1]
    if np.all(np.abs(np.diff(seg_q, axis=0)) == 0):
        return None
    keep = np.concatenate([[True], np.any(np.diff(seg_q, axis=0) != 0, axis=1)])
    at, arrive, dev, inserted = _time_segment(seg_q[keep], velocity, acceleration, tolerance)
    rows_kept = np.arange(a, b + 1)[keep]
    rows = np.arange(a + 1, b + 1)  # a row equal to the one before it arrives with it
    arrive_rows = arrive[np.searchsorted(rows_kept, rows, side="right") - 1]
    dur = float(arrive[-1])
    regular = np.arange(dt, dur, dt)
    # ``arange`` can end a hair before ``dur`` (or an arrival): that sample would share the
    # arrival's time to the CSV's resolution, so the arrival (the exact row) stands alone
    gap = np.abs(regular[:, None] - arrive[None, 1:]).min(axis=1, initial=np.inf)
    grid_t = np.unique(np.concatenate([regular[gap >= MIN_GAP_DT * dt], arrive[1:]]))
    grid_t = grid_t[grid_t > 0]
    grid_steps = rows_kept[np.searchsorted(arrive, grid_t - 1e-12)]
    grid_q = at(grid_t).reshape(-1, d)
    grid_q[-1] = q[b]  # the stop itself, exactly
    return arrive_rows, grid_t, grid_steps, grid_q, Segment(a, b, dur, dev, inserted)


def constant_speed_time(
    points: ArrayLike, n_welds: int, *, speed: float = DEFAULT_TCP_SPEED, weld_time: float = 0.0
) -> float:
    """s to travel the Cartesian polyline ``points (n, 3)`` mm at ``speed`` mm/s, plus
    ``n_welds * weld_time``: the constant-TCP-speed comparison (module docstring)."""
    if not (math.isfinite(speed) and speed > 0):
        raise ConfigError(
            f"TCP speed must be a finite number of mm/s > 0, got {speed!r}", field="tcp_speed"
        )
    length = polyline_length(np.asarray(points, dtype=np.float64).reshape(-1, 3))
    return length / speed + n_welds * check_weld_time(weld_time)


def pair_time(dq: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike) -> NDArray[np.float64]:
    """Time-optimal rest-to-rest time (s) of straight joint-space moves ``dq (..., d)`` rad.

    On a straight joint-space line ``q0 + s dq``, ``s`` in [0, 1], the box limits become
    ``|s'| <= V = min_j v_j / |dq_j|`` and ``|s''| <= A = min_j a_j / |dq_j|``; the optimum is
    the trapezoid (triangle when ``V^2 / A > 1``): ``T = 1 / V + V / A`` or ``2 / sqrt(A)``.
    This is what :func:`time_route` gives for a two-waypoint segment (tested against it), and
    the cheap cost of ``--cost time`` between two welds' configurations.
    """
    vel, acc = check_limits(velocity, acceleration)
    D = np.abs(np.asarray(dq, dtype=np.float64))
    with np.errstate(divide="ignore"):
        V = np.min(np.where(D > 0, vel / D, np.inf), axis=-1)
        A = np.min(np.where(D > 0, acc / D, np.inf), axis=-1)
    trap = 1.0 / V + V / A
    tri = 2.0 / np.sqrt(A)
    out = np.where(V * V / A >= 1.0, tri, trap)
    return np.where(np.isfinite(V), out, 0.0)
