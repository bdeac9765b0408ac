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
3. times the route (:func:`weldplan.robot.timing.time_route`) and takes each move's TCP speed as
   the peak TCP speed of the timed trajectory on that move (FK of the samples), so the program
   asks for the speeds the cycle time assumed;
4. frames the route by a joint move to the first virtual joint (from wherever the robot is) and
   a retreat to the last one, both rows of the verified route; every other move is linear (the
   route was verified as straight Cartesian segments and its blends for linear moves).

Named deviation: the timing model moves in joint space between waypoints (a spline within
``tolerance`` rad of the joint polyline), the program's linear moves follow the Cartesian lines;
:attr:`ProgramBuild.tcp_deviation` is how far the timed TCP strays from those lines (mm).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import PlanningError
from weldplan.io.blending import RAPID_ZONES, allowed_radii, route_clearance
from weldplan.io.posts.config import arm_flags
from weldplan.io.posts.program import RobotProgram, Target
from weldplan.robot.timing import (
    DEFAULT_TCP_SPEED,
    DEFAULT_TOLERANCE_RAD,
    TimedTrajectory,
    constant_speed_time,
    time_route,
)

log = logging.getLogger(__name__)

#: FK of a row's joint vector must put the TCP this close (mm) to the route's waypoint
ROW_TOLERANCE_MM = 0.01
#: speed (mm/s) of the joint move to the approach point, from wherever the robot is
APPROACH_SPEED = 250.0


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
    """

    program: RobotProgram
    timing: TimedTrajectory
    constant_speed_time: float
    tcp_speed: float
    tcp_deviation: float


def _segment_distance(P: NDArray, A: NDArray, B: NDArray) -> NDArray:
    """``(m,)`` distance of points ``P (m, 3)`` to segments ``A -> B`` (each ``(m, 3)``)."""
    ab = B - A
    den = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", P - A, ab) / den, 0.0, 1.0)
    return np.linalg.norm(P - (A + t[:, None] * ab), axis=1)


def robot_program(
    route: Any,
    q: ArrayLike,
    robot: Any,
    T_flange_tcp: ArrayLike,
    *,
    part: Any,
    tool_mass: float,
    tool_cog: ArrayLike,
    weld_time: float = 0.0,
    clearance: float | None = None,
    tolerance: float = DEFAULT_TOLERANCE_RAD,
    tcp_speed: float = DEFAULT_TCP_SPEED,
    name: str = "weldplan_route",
) -> ProgramBuild:
    """Build the program of ``route`` driven by joint vectors ``q (n, 6)`` rad (module docstring).

    Parameters
    ----------
    route
        The verified :class:`~weldplan.weld.route.Route` (``n`` waypoint rows).
    robot
        :class:`~weldplan.robot.model.Robot` placed in the part frame (its velocity and
        acceleration limits already scaled as the run asks).
    T_flange_tcp
        ``(4, 4)`` mm: the TCP in the flange frame.
    part
        Mesh, Cell or CollisionModel for the blend radii.
    tool_mass, tool_cog
        kg and ``(3,)`` mm in the flange frame.
    """
    from weldplan.io.export import route_rows

    rows = route_rows(route)
    Q = np.asarray(q, dtype=np.float64).reshape(-1, 6)
    n = len(rows)
    if len(Q) != n:
        raise PlanningError(f"{len(Q)} joint vectors for a route of {n} waypoints")
    Tft = np.asarray(T_flange_tcp, dtype=np.float64).reshape(4, 4)
    poses = robot.fk(Q) @ Tft  # (n, 4, 4) TCP in the part frame
    pts = np.array([[r["x"], r["y"], r["z"]] for r in rows], dtype=np.float64)
    err = np.linalg.norm(poses[:, :3, 3] - pts, axis=1)
    if err.max() > ROW_TOLERANCE_MM:
        k = int(np.argmax(err))
        raise PlanningError(
            f"forward kinematics puts the TCP {err[k]:.3g} mm from route row {k} "
            f"(tolerance {ROW_TOLERANCE_MM} mm): the joint route is not the verified route"
        )
    welds = np.array([k for k, r in enumerate(rows) if r["kind"] == "weld"], dtype=np.int64)
    # program order: approach (row 1), every row, retreat (row n - 2)
    order = [1, *range(n), n - 2] if n >= 3 else list(range(n))
    kinds = (
        (["approach"] + [r["kind"] for r in rows] + ["retreat"])
        if n >= 3
        else [r["kind"] for r in rows]
    )
    c = route_clearance(route, clearance)
    radii = allowed_radii(pts[order], [k == "via" for k in kinds], part, c)
    stop_rows = np.ones(n, dtype=bool)
    off = 1 if n >= 3 else 0
    stop_rows[:] = radii[off : off + n] < RAPID_ZONES["z0"]

    timing = time_route(
        Q,
        robot.velocity,
        robot.acceleration,
        weld_rows=welds,
        stops=stop_rows,
        weld_time=weld_time,
        tolerance=tolerance,
        joint_names=tuple(robot.joint_names),
    )
    speed, dev = _tcp_speeds(robot, Tft, timing, pts, n)
    flags = arm_flags(robot, Q)
    targets = []
    for i, (row, kind) in enumerate(zip(order, kinds, strict=True)):
        if kind == "approach":
            v, move = APPROACH_SPEED, "joint"
        elif i == off:  # the first weld, reached from the approach point: row 1 -> 0 reversed
            v, move = speed[min(1, n - 1)], "linear"
        elif kind == "retreat":
            v, move = speed[n - 1], "linear"
        else:
            v, move = speed[row], "linear"
        if not n >= 3 and i == 0:
            move = "joint"
        targets.append(
            Target(
                kind=kind,
                row=int(row),
                joint_id=str(rows[row]["joint_id"]) if kind == "weld" else "",
                pose=poses[row],
                q=Q[row],
                flags=flags[row],
                move=move,
                blend=float(radii[i]),
                speed=float(max(v, 1.0)),
            )
        )
    cst = constant_speed_time(pts, len(welds), speed=tcp_speed, weld_time=timing.weld_time)
    notes = (
        f"{len(route.joint_ids)} weld joints, {len(targets)} targets, route length "
        f"{route.length:.2f} mm, order {'-'.join(route.order)}.",
        f"Cycle time {timing.total:.2f} s (toppra, URDF velocity and the run's acceleration "
        f"limits, {timing.weld_time:g} s a weld; first weld to the end of the last, without the "
        f"approach and retreat); at a constant {tcp_speed:g} mm/s TCP speed: {cst:.2f} s.",
        "Speeds: the peak TCP speed of each move in the timed trajectory. Zones: a via flies by "
        f"within its free margin (distance to the part - {c:g} mm clearance), else fine.",
        "Configurations: of the planned joint values (IK branch), kept by the controller.",
    )
    mass = float(tool_mass)
    program = RobotProgram(
        name=name,
        robot=robot.name,
        joint_names=tuple(robot.joint_names),
        targets=tuple(targets),
        tool_frame=Tft,
        tool_mass=mass,
        tool_cog=np.asarray(tool_cog, dtype=np.float64).reshape(3),
        part_frame=np.linalg.inv(robot.base),
        weld_time=timing.weld_time,
        notes=notes,
    )
    return ProgramBuild(program, timing, cst, float(tcp_speed), dev)


def _tcp_speeds(
    robot: Any, Tft: NDArray, timing: TimedTrajectory, pts: NDArray, n: int
) -> tuple[NDArray[np.float64], float]:
    """``(n,)`` peak TCP speed (mm/s) of the move into each row, and the largest TCP distance
    (mm) of the timed samples from their Cartesian segment."""
    P = (robot.fk(timing.q) @ Tft)[:, :3, 3]
    dt = np.diff(timing.t)
    moving = dt > 1e-12
    v = np.zeros(len(dt))
    v[moving] = np.linalg.norm(np.diff(P, axis=0)[moving], axis=1) / dt[moving]
    step = timing.step[1:]
    speed = np.zeros(n)
    np.maximum.at(speed, step, v)
    s = np.clip(timing.step, 1, n - 1)
    dev = _segment_distance(P, pts[s - 1], pts[s]) if n > 1 else np.zeros(1)
    return speed, float(dev.max())
