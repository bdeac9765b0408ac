"""From a robot's route to a :class:`~weldplan.io.posts.program.RobotProgram` (and its timing).

:func:`robot_program` takes the point-tip route (its waypoint rows,
:func:`weldplan.io.export.route_rows`), the joint vector the robot has at every row, the tool
(flange -> TCP, mass, centre of gravity) and the part, and

1. checks that forward kinematics of every joint vector puts the TCP on its route row
   (:data:`ROW_TOLERANCE_MM`): a joint route that is not the verified route is an error, not a
   program;
2. chooses the blend radius of every via point from its free margin
   (:func:`weldplan.io.blending.allowed_radii`); where no RAPID zone fits (``< z0``, 0.3 mm) the
   point is an exact stop, and the cycle-time model stops there too;
3. times the route (:func:`weldplan.robot.program.time_route`) and takes each move's TCP speed as
   the peak TCP speed of the timed trajectory on that move (FK of the samples), so the program
   asks for the speeds the cycle time assumed;
4. frames the route by a joint move to the first virtual joint (from wherever the robot is) and
   a retreat to the last one, both rows of the verified route.

Moves (``moves``): the joint route (:class:`~weldplan.robot.route.RobotRoute`) has rows on the
route (``exact``: FK puts the TCP on the route's pose) and, on legs re-planned in joint space,
rows that are not. A target that is not exact is always a joint move with an exact stop (only
its joint path was checked). Between exact rows:

* ``"linear"`` (default): ``MoveL`` / ``LIN`` where the Cartesian move itself is verified
  (:func:`weldplan.robot.route.check_linear_moves`: IK along the line at 5 mm / 2 deg, same
  branch, no flip, joint limits, no wrist singularity, robot links + tool against the part), a
  joint move otherwise; blended where the free margin allows (the blend argument of
  :mod:`weldplan.io.blending` is for linear moves). Named deviation: the timing moves in joint
  space between rows; :attr:`ProgramBuild.tcp_deviation` is how far that joint path's TCP
  strays from the Cartesian lines (mm); ``line_tolerance`` (1 mm by default) also refuses a
  linear move whose joint path strays more, so the cycle time is that of the program.
* ``"joint"``: ``MoveJ`` / ``PTP`` everywhere, every target an exact stop (no joint-space blend
  is verified): exactly the joint path the robot check verified, and the timing of it.
"""

from __future__ import annotations

import logging
from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.io.blending import RAPID_ZONES, allowed_radii, route_clearance
from weldplan.io.posts.config import arm_flags
from weldplan.io.posts.program import RobotProgram, Target
from weldplan.robot.program.timing import (
    TimedTrajectory,
    constant_speed_time,
    time_route,
)
from weldplan.robot.settings import (  # noqa: F401 (LINE_TOLERANCE_MM re-exported)
    LINE_TOLERANCE_MM,
    ProgramSettings,
    ToolOnRobot,
)

log = logging.getLogger(__name__)

#: FK of a row's joint vector must put the TCP this close (mm) to the route's waypoint
ROW_TOLERANCE_MM = 0.01
#: samples per move for :func:`joint_line_deviation`
LINE_SAMPLES = 16
#: speed (mm/s) of the joint move to the approach point, from wherever the robot is
APPROACH_SPEED = 250.0
#: rad: a row standing for a weld not welded within this of the joint segment between its
#: neighbours is a pass, not a target (:func:`_without_passes`)
PASS_TOL_RAD = 1e-9


@dataclass(frozen=True, eq=False)
class ProgramBuild:
    """The program, its timing and the numbers a summary reports.

    Attributes
    ----------
    program
        What the posts write.
    timing
        The timed trajectory over the route's rows.
    constant_speed_time
        s: the same route at one constant TCP speed (:attr:`tcp_speed`) plus the same dwell.
    tcp_speed
        mm/s of that comparison.
    tcp_deviation
        mm: largest distance of the timed TCP (FK of the samples) from its Cartesian segment.
    skipped
        Welds the joint route does not serve (no exact row): passed without welding, named in
        the program's header, never a target.
    row
        ``(k,) int``: the route row of each joint row the program and its timing run over (the
        joint route without the rows it only passes, :func:`_without_passes`; the ``step`` of
        :func:`weldplan.io.trajectory.trajectory_csv_text`).
    """

    program: RobotProgram
    timing: TimedTrajectory
    constant_speed_time: float
    tcp_speed: float
    tcp_deviation: float
    skipped: tuple[str, ...] = ()
    row: NDArray[np.int64] | None = None

    def welded_ids(self) -> tuple[str, ...]:
        """The weld id of each of :attr:`timing`'s weld rows, in their order: the welds the
        program welds (a weld it passes, :attr:`skipped`, is not one; the route's
        ``weld_ids`` name those too)."""
        ids = self.weld_ids_by_row()
        return tuple(str(ids[int(w)]) for w in self.timing.weld_rows)

    def weld_ids_by_row(self) -> dict[int, str]:
        """``{timed row: weld id}``: the program's weld targets named by the timed rows
        (:attr:`row`) they stand on."""
        by_route = {t.row: t.joint_id for t in self.program.targets if t.kind == "weld"}
        rows = self.row if self.row is not None else range(len(self.timing.row_times))
        return {i: by_route[int(r)] for i, r in enumerate(rows) if int(r) in by_route}


def _segment_distance(P: NDArray, A: NDArray, B: NDArray) -> NDArray:
    """``(m,)`` distance of points ``P (m, 3)`` to segments ``A -> B`` (each ``(m, 3)``)."""
    ab = B - A
    den = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", P - A, ab) / den, 0.0, 1.0)
    return np.linalg.norm(P - (A + t[:, None] * ab), axis=1)


def joint_line_deviation(
    robot: Any, Tft: NDArray[np.float64], qa: ArrayLike, qb: ArrayLike
) -> NDArray[np.float64]:
    """``(m,)`` mm: the largest distance of the TCP on the joint-space line ``qa -> qb``
    (``(m, 6)`` each, :data:`LINE_SAMPLES` samples, FK of the URDF chain) from the Cartesian
    segment between its ends: how far the checked joint path strays from a linear move."""
    A = np.asarray(qa, dtype=np.float64).reshape(-1, 6)
    B = np.asarray(qb, dtype=np.float64).reshape(-1, 6)
    if len(A) == 0:
        return np.zeros(0)
    f = np.linspace(0.0, 1.0, LINE_SAMPLES + 1)
    S = A[:, None, :] + f[None, :, None] * (B - A)[:, None, :]  # (m, s, 6)
    P = (robot.fk(S.reshape(-1, 6)) @ Tft)[:, :3, 3].reshape(len(A), len(f), 3)
    a = np.repeat(P[:, :1], len(f), axis=1).reshape(-1, 3)
    b = np.repeat(P[:, -1:], len(f), axis=1).reshape(-1, 3)
    d = _segment_distance(P.reshape(-1, 3), a, b).reshape(len(A), len(f))
    return d.max(axis=1)


def _exact_index(row: NDArray[np.int64], exact: NDArray[np.bool_], n: int) -> NDArray[np.int64]:
    """``(n,)``: for every route row the first joint-route row on it that is exact, -1 where none
    is (a weld the robot cannot serve: the joint route interpolates across it)."""
    idx = np.full(n, -1, dtype=np.int64)
    for i in range(len(row) - 1, -1, -1):
        if exact[i]:
            idx[row[i]] = i
    return idx


def _first_on(row: NDArray[np.int64], at: NDArray[np.int64], r: int, after: bool) -> int:
    """The joint row standing for route row ``r``: its exact one, else the first on it, else
    (a via of a leg re-planned in joint space, which has no row of its own) the first joint row
    after it (``after``) or the last before it."""
    if at[r] >= 0:
        return int(at[r])
    on = np.flatnonzero(row == r)
    if len(on):
        return int(on[0])
    return int(np.flatnonzero(row > r)[0]) if after else int(np.flatnonzero(row < r)[-1])


def robot_program(
    route: Any,
    q: ArrayLike,
    robot: Any,
    tool: ToolOnRobot,
    *,
    part: Any,
    row: ArrayLike | None = None,
    exact: ArrayLike | None = None,
    settings: ProgramSettings | None = None,
    checker: Any = None,
    contact_radius: float | None = None,
) -> ProgramBuild:
    """Build the program of ``route`` driven by the joint route ``q`` (module docstring).

    Parameters
    ----------
    route
        The verified :class:`~weldplan.weld.route.Route` (``n`` waypoint rows).
    q
        ``(k, 6)`` rad: the joint route, ``k >= n``.
    robot
        :class:`~weldplan.robot.model.Robot` placed in the part frame (its velocity and
        acceleration limits already scaled as the run asks).
    tool
        The tool on the flange (:class:`~weldplan.robot.settings.ToolOnRobot`): the flange ->
        TCP transform, the load the program declares (``mass`` kg and ``cog`` ``(3,)`` mm in the
        flange frame, required) and the tool mesh for the linear moves' collision check (links
        only without it).
    part
        Mesh, Cell or CollisionModel for the blend radii (and, a mesh or Cell, for the linear
        moves' collision check).
    row, exact
        ``(k,)``: the route row each joint row belongs to and whether it is on the route
        (:class:`~weldplan.robot.route.RobotRoute`); default ``arange(n)`` and all true.
    settings
        :class:`~weldplan.robot.settings.ProgramSettings`: the moves (module docstring), the
        line tolerance of a linear move, the weld time, the blend clearance, the timing's
        tolerance, the comparison's TCP speed, the program's name (default: its defaults).
    checker, contact_radius
        The linear moves' collision check: ``checker`` (a
        :class:`~weldplan.robot.collision.RobotCollision`), else one built from the part mesh and
        the tool with the contact zone ``contact_radius`` mm (default the pose search's) exempt.

    A weld without an exact joint row (one the robot cannot serve, which the robot route
    interpolates across in joint space or passes on a detour) is passed without welding and
    listed in :attr:`ProgramBuild.skipped` and the program's header; no target moves to it
    (:func:`_without_passes`: joint rows held at one configuration and interpolated passes are
    not targets; the joint path is unchanged).

    Raises
    ------
    ConfigError
        A tool without its load (``mass``).
    PlanningError
        An exact row whose FK is off its route waypoint by more than :data:`ROW_TOLERANCE_MM`,
        a weld row with no joint row at all.
    """
    from weldplan.io.export import route_rows

    s = ProgramSettings() if settings is None else settings
    if tool.mass is None:
        raise ConfigError("the program declares the tool's load: give its mass", field="mass")
    rows = route_rows(route)
    n = len(rows)
    Q, R, X = _joint_rows(q, row, exact, n)
    _check_weld_rows(rows, R)
    Q, R, X = _without_passes(Q, R, X, rows)
    k = len(Q)
    at = _exact_index(R, X, n)  # route row -> joint row (-1: not served)
    Tft = tool.flange_tcp
    poses = robot.fk(Q) @ Tft  # (k, 4, 4) TCP in the part frame
    pts = np.array([[r["x"], r["y"], r["z"]] for r in rows], dtype=np.float64)
    _check_rows(poses, pts, at)
    kind_of = [rows[int(r)]["kind"] if X[i] and at[R[i]] == i else "via" for i, r in enumerate(R)]
    if s.home:
        R = _home_rows(R, X, n)
        kind_of[0] = kind_of[-1] = "home"
    po = _program_order(R, at, n, k, kind_of, s.home)
    linear = np.zeros(len(po.order), dtype=bool)
    if s.moves == "linear":
        if checker is None:
            checker = _checker(robot, part, tool, contact_radius)
        linear = _linear_moves(robot, Tft, Q, X, po.order, s.line_tolerance, checker)
    c = route_clearance(route, s.clearance)
    radii = _blend_radii(poses[po.order, :3, 3], po.kinds, linear, part, c)
    off = 1 if po.framed else 0
    stops = radii[off : off + k] < RAPID_ZONES["z0"]
    welds, skipped = _served_welds(rows, R, at)

    timing = time_route(
        Q,
        robot.velocity,
        robot.acceleration,
        weld_rows=welds,
        stops=stops,
        weld_time=s.weld_time,
        tolerance=s.tolerance,
        joint_names=tuple(robot.joint_names),
    )
    speed, dev = _tcp_speeds(poses[:, :3, 3], robot, Tft, timing, linear[off : off + k])
    targets = _targets(rows, R, at, Q, poses, arm_flags(robot, Q), po, linear, radii, speed)
    cst = constant_speed_time(pts, len(welds), speed=s.tcp_speed, weld_time=timing.weld_time)
    if skipped:
        log.warning("the program passes %d weld(s) without welding: %s", len(skipped), skipped)
    notes = _notes(route, len(targets), timing, cst, s, c, skipped)
    program = _program(s.name, robot, targets, tool, timing.weld_time, notes)
    return ProgramBuild(program, timing, cst, float(s.tcp_speed), dev, tuple(skipped), R)


def _program(
    name: str,
    robot: Any,
    targets: list[Target],
    tool: ToolOnRobot,
    weld_time: float,
    notes: tuple[str, ...],
) -> RobotProgram:
    """The :class:`RobotProgram` of ``targets``: the tool frame (the flange -> TCP transform,
    mm) and load (kg, ``(3,)`` mm), the work object = the part frame in the robot base frame."""
    return RobotProgram(
        name=name,
        robot=robot.name,
        joint_names=tuple(robot.joint_names),
        targets=tuple(targets),
        tool_frame=tool.flange_tcp,
        tool_mass=float(tool.mass),  # type: ignore[arg-type]
        tool_cog=np.asarray(tool.cog, dtype=np.float64).reshape(3),
        part_frame=np.linalg.inv(robot.base),
        weld_time=weld_time,
        notes=notes,
    )


def _joint_rows(
    q: ArrayLike, row: ArrayLike | None, exact: ArrayLike | None, n: int
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]:
    """``(Q (k, 6) rad, row (k,), exact (k,))`` of the joint route, with the defaults of
    :func:`robot_program`; PlanningError when they do not map onto ``n`` route rows."""
    Q = np.asarray(q, dtype=np.float64).reshape(-1, 6)
    k = len(Q)
    R = np.arange(k, dtype=np.int64) if row is None else np.asarray(row, dtype=np.int64)
    X = np.ones(k, dtype=bool) if exact is None else np.asarray(exact, dtype=bool)
    if len(R) != k or len(X) != k or (k and (R.min() < 0 or R.max() >= n)):
        raise PlanningError(f"{k} joint rows do not map onto a route of {n} waypoints")
    return Q, R, X


def _blend_radii(
    points: NDArray[np.float64], kinds: list[str], linear: NDArray[np.bool_], part: Any, c: float
) -> NDArray[np.float64]:
    """Blend radius (mm) of every program target at ``points (m, 3)``: a via point may fly by
    only between two linear moves (the blend argument of :mod:`weldplan.io.blending` is for
    lines), within its free margin at clearance ``c`` mm."""
    nxt = np.concatenate([linear[1:], [False]])
    cand = [kd == "via" and a and b for kd, a, b in zip(kinds, linear, nxt, strict=True)]
    return allowed_radii(points, cand, part, c)


def _check_weld_rows(rows: list[dict], R: NDArray[np.int64]) -> None:
    """PlanningError for a weld with no joint row at all."""
    missing = [j for j, r in enumerate(rows) if r["kind"] == "weld" and not np.any(R == j)]
    if missing:
        raise PlanningError(f"the joint route has no row for the weld at route row {missing[0]}")


def _without_passes(
    Q: NDArray[np.float64], R: NDArray[np.int64], X: NDArray[np.bool_], rows: list[dict]
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.bool_]]:
    """The joint rows the program moves to: without the rows that are not exact and either
    repeat the joint values of the row before (a configuration held while the route's later
    rows pass: no motion) or stand for a weld that is not welded and lie on the joint segment
    from the row before to the next (an interpolated pass, :data:`PASS_TOL_RAD`). The joint
    path is the same; a weld not welded is never moved to (the header names it)."""
    weld = np.array([r["kind"] == "weld" for r in rows], dtype=bool)
    welded = set(R[X & weld[R]].tolist())
    keep = np.ones(len(Q), dtype=bool)
    last = 0
    for i in range(1, len(Q)):
        passed = not X[i] and (
            np.array_equal(Q[i], Q[last])
            or (
                weld[R[i]]
                and int(R[i]) not in welded
                and i + 1 < len(Q)
                and _on_segment(Q[i], Q[last], Q[i + 1])
            )
        )
        keep[i] = not passed
        last = last if passed else i
    return Q[keep], R[keep], X[keep]


def _on_segment(p: NDArray, a: NDArray, b: NDArray) -> bool:
    """Whether ``p (6,)`` lies on the joint segment ``a -> b`` within :data:`PASS_TOL_RAD`."""
    d = b - a
    den = float(d @ d)
    t = 0.0 if den == 0.0 else min(max(float((p - a) @ d) / den, 0.0), 1.0)
    return bool(np.abs(a + t * d - p).max() <= PASS_TOL_RAD)


def _served_welds(
    rows: list[dict], R: NDArray[np.int64], at: NDArray[np.int64]
) -> tuple[NDArray[np.int64], list[str]]:
    """The joint rows where the robot welds, and the ids of the welds it passes without
    welding (no exact joint row)."""
    weld_rows = [j for j, r in enumerate(rows) if r["kind"] == "weld"]
    welds = at[[j for j in weld_rows if at[j] >= 0]]
    skipped = [str(rows[j]["joint_id"]) for j in weld_rows if at[j] < 0]
    return welds, skipped


def _check_rows(poses: NDArray, pts: NDArray, at: NDArray[np.int64]) -> None:
    """FK of every served row's joint vector must put the TCP on its route waypoint."""
    served = at >= 0
    err = np.zeros(len(pts))
    err[served] = np.linalg.norm(poses[at[served], :3, 3] - pts[served], axis=1)
    if len(pts) and err.max() > ROW_TOLERANCE_MM:
        j = int(np.argmax(err))
        raise PlanningError(
            f"forward kinematics puts the TCP {err[j]:.3g} mm from route row {j} "
            f"(tolerance {ROW_TOLERANCE_MM} mm): the joint route is not the verified route"
        )


@dataclass(frozen=True)
class _ProgramOrder:
    """The joint rows in program order (``order``), their kinds (``"approach"``, ``"weld"``,
    ``"via"``, ``"retreat"``...) and whether an approach and a retreat frame them."""

    order: list[int]
    kinds: list[str]
    framed: bool


def _home_rows(R: NDArray[np.int64], X: NDArray[np.bool_], n: int) -> NDArray[np.int64]:
    """The route rows of a joint route that starts and ends at home
    (:mod:`weldplan.robot.route.home`), its two home rows renamed ``-1`` (before the route) and
    ``n`` (after it), so that a target and an interlock signal at home are not those of the
    first or last weld; PlanningError when the first or last row is on the route."""
    if len(R) < 2 or X[0] or X[-1]:
        raise PlanningError("a program from home needs a joint route that starts and ends there")
    out = R.copy()
    out[0], out[-1] = -1, n
    return out


def _program_order(
    R: NDArray[np.int64], at: NDArray[np.int64], n: int, k: int, kind_of: list[str],
    home: bool = False,
) -> _ProgramOrder:  # fmt: skip
    """Joint rows in program order and their kinds: approach (route row 1), every joint row,
    retreat (route row ``n - 2``) when the route has at least three rows; from ``home``, every
    joint row (the first and last are home)."""
    if n < 3 or home:
        return _ProgramOrder(list(range(k)), list(kind_of), False)
    order = [_first_on(R, at, 1, True), *range(k), _first_on(R, at, n - 2, False)]
    return _ProgramOrder(order, ["approach", *kind_of, "retreat"], True)


def _checker(robot: Any, part: Any, tool: ToolOnRobot, contact_radius: float | None) -> Any:
    """Robot (+ tool) against the part mesh, or ``None`` where the part is no mesh (then no
    move is linear)."""
    import trimesh

    mesh = getattr(part, "part", part)
    if not isinstance(mesh, trimesh.Trimesh):
        log.warning("no part mesh for the linear moves' collision check: joint moves only")
        return None
    from weldplan.robot.collision.checker import RobotCollision
    from weldplan.tool.poses.plan import DEFAULT_CONTACT_RADIUS

    cr = DEFAULT_CONTACT_RADIUS if contact_radius is None else float(contact_radius)
    return RobotCollision(robot, mesh, tool.tool, tool.flange_tcp, contact_radius=cr)


def _linear_moves(
    robot: Any,
    Tft: NDArray,
    Q: NDArray,
    X: NDArray[np.bool_],
    order: list[int],
    line_tolerance: float | None,
    checker: Any,
) -> NDArray[np.bool_]:
    """``(len(order),) bool``: the move into each program target is linear: both ends exact
    rows (the first move comes from wherever the robot is), the Cartesian move itself verified
    (:func:`weldplan.robot.route.check_linear_moves`) and, with ``line_tolerance``, the checked
    joint path within it of the Cartesian line."""
    from weldplan.robot.route.linear import check_linear_moves

    ex = X[order]
    qa, qb = Q[order[:-1]], Q[order[1:]]
    cand = ex[1:] & ex[:-1]
    if line_tolerance is not None:
        cand &= joint_line_deviation(robot, Tft, qa, qb) <= line_tolerance
    cand &= np.any(qa != qb, axis=1)  # a move of zero length stays a joint move
    idx = np.flatnonzero(cand)
    checks = check_linear_moves(robot, Tft, qa[idx], qb[idx], checker=checker)
    cand[idx] = checks.ok
    refused = Counter(r for r in checks.reason if r != "ok")
    if refused:
        log.info("linear moves refused: %s", dict(refused))
    return np.concatenate([[False], cand])


def _targets(
    rows: list[dict],
    R: NDArray[np.int64],
    at: NDArray[np.int64],
    Q: NDArray,
    poses: NDArray,
    flags: Any,
    po: _ProgramOrder,
    linear: NDArray[np.bool_],
    radii: NDArray,
    speed: NDArray,
) -> list[Target]:
    """The program's targets, in program order, with the speeds of the timed trajectory."""
    k = len(Q)
    targets = []
    for i, (j, kind) in enumerate(zip(po.order, po.kinds, strict=True)):
        if kind == "approach":
            v = APPROACH_SPEED
        elif po.framed and i == 1:  # the first weld, from the approach point: row 1 -> 0 reversed
            v = speed[min(_first_on(R, at, 1, True), k - 1)]
        elif kind == "retreat":
            v = speed[k - 1]
        else:
            v = speed[j]
        targets.append(
            Target(
                kind=kind,
                row=int(R[j]),
                joint_id=str(rows[int(R[j])]["joint_id"]) if kind == "weld" else "",
                pose=poses[j],
                q=Q[j],
                flags=flags[j],
                move="linear" if linear[i] else "joint",
                blend=float(radii[i]),
                speed=float(max(v, 1.0)),
            )
        )
    return targets


def _notes(
    route: Any,
    n_targets: int,
    timing: TimedTrajectory,
    cst: float,
    s: ProgramSettings,
    c: float,
    skipped: list[str],
) -> tuple[str, ...]:
    """The header comment lines of the program."""
    miss = (
        (f"Not welded (the robot cannot serve them; no target moves to them): "
         f"{', '.join(skipped)}.",)  # fmt: skip
        if skipped
        else ()
    )
    span = (
        "from home to home, the home legs joint moves"
        if s.home
        else "first weld to the end of the last, without the approach and retreat"
    )
    return miss + (
        f"{len(route.joint_ids)} weld joints, {n_targets} targets, route length "
        f"{route.length:.2f} mm, order {'-'.join(route.order)}.",
        f"Cycle time {timing.total:.2f} s (toppra, URDF velocity and the run's acceleration "
        f"limits, {timing.weld_time:g} s a weld; {span}); at a constant {s.tcp_speed:g} mm/s "
        f"TCP speed: {cst:.2f} s.",
        f"Moves between route rows: {s.moves}. Speeds: the peak TCP speed of each move in the "
        "timed trajectory.",
        f"Zones: a linear move's via flies by within its free margin (distance to the part - "
        f"{c:g} mm clearance), else fine; joint moves stop.",
        "Configurations: of the planned joint values (IK branch), kept by the controller.",
    )


def _tcp_speeds(
    P_rows: NDArray, robot: Any, Tft: NDArray, timing: TimedTrajectory, linear: NDArray
) -> tuple[NDArray[np.float64], float]:
    """``(k,)`` peak TCP speed (mm/s) of the move into each joint row, and the largest TCP
    distance (mm) of the timed samples from the Cartesian segment of a linear move
    (``linear (k,)``: the move into that joint row is linear)."""
    k = len(P_rows)
    P = (robot.fk(timing.q) @ Tft)[:, :3, 3]
    dt = np.diff(timing.t)
    moving = dt > 1e-12
    v = np.zeros(len(dt))
    v[moving] = np.linalg.norm(np.diff(P, axis=0)[moving], axis=1) / dt[moving]
    speed = np.zeros(k)
    np.maximum.at(speed, timing.step[1:], v)
    if k < 2:
        return speed, 0.0
    s = np.clip(timing.step, 1, k - 1)
    both = linear[s] & (timing.step > 0)
    if not np.any(both):
        return speed, 0.0
    dev = _segment_distance(P[both], P_rows[s - 1][both], P_rows[s][both])
    return speed, float(dev.max())
