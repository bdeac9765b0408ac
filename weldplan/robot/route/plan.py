"""From a tool-aware route to a verified joint-space route: :func:`plan_robot_route`.

::

    robot = load_robot(".../kr150r3100_2.urdf")
    tool = ToolOnRobot(tool_flange_tcp(robot, ".../spot_welding_gun.urdf", "nozzle_tip"), gun)
    rr = plan_robot_route(route, poses, robot, tool=tool, cell=RobotCell(part=cell.part))

Steps: TCP poses of every route waypoint (weld poses, slerped between them; or the caller's, as
for a route along the gun's transitions, :mod:`weldplan.robot.route.gunpath`) -> flange poses ->
base given or searched (:mod:`weldplan.robot.placement.base`, :mod:`weldplan.robot.placement.reach`)
-> at each weld, the usable IK branches on which no link and no part of the tool outside its contact
zone touches the part (a weld with none: ``collision``, the body in ``detail``) -> one IK solution
per waypoint, continuous (:mod:`weldplan.robot.route.configs`) -> robot + tool against the part
along the joint path (:mod:`weldplan.robot.collision.checker`) -> blocked legs detoured through
retract poses, in joint space (straight, tucked arm, or OMPL
:func:`weldplan.motion.sampling.plan_rn`), a weld whose leg has no detour dropped with its reason
(:mod:`weldplan.robot.route.replan`) -> verification that shares nothing with the planner: FK of the
URDF chain at every exact row equals the route's TCP pose, and the collision check of the final
path.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from weldplan.errors import ConfigError, InputError, PlanningError
from weldplan.motion.roadmap import RoadmapSettings
from weldplan.robot.collision.bodies import Hit
from weldplan.robot.collision.checker import RobotCollision
from weldplan.robot.collision.selfcollision import cell_floor, hit_words
from weldplan.robot.model.arm import Robot
from weldplan.robot.model.urdf import chain_transform
from weldplan.robot.placement.base import free_branches, place
from weldplan.robot.placement.reach import COLLISION, NO_POSE, OK, Placement, classify
from weldplan.robot.placement.roadmaps import LegRoadmap
from weldplan.robot.route.configs import RobotRoute, joint_path
from weldplan.robot.route.replan import Detour
from weldplan.robot.route.walk import assemble
from weldplan.robot.settings import (  # noqa: F401 (the route's defaults, re-exported)
    REPLAN_PLANNER,
    REPLAN_TIME_S,
    ROADMAP,
    SEARCH_TOP,
    JointRouteSettings,
    RobotCell,
    ToolOnRobot,
)

log = logging.getLogger(__name__)

#: mm / deg: the verification tolerance of an exact row's FK against the route's pose
POSE_TOL_MM = 1e-6
POSE_TOL_DEG = 1e-6


def tool_flange_tcp(
    robot: Robot, tool_urdf: str | PathLike[str], tcp: str | None = None
) -> NDArray[np.float64]:
    """``(4, 4)`` mm: the TCP in the robot's flange frame for a tool URDF whose root link is its
    mounting frame (``robot.mount @ root->tcp``); ``tcp`` names the TCP joint or link (default:
    the last fixed joint of the file)."""
    if tcp is None:
        from weldplan.robot.model.urdf import parse_urdf

        _, _, joints = parse_urdf(tool_urdf)
        fixed = [j for j in joints if j.kind == "fixed"]
        if not fixed:
            raise ConfigError("the tool URDF has no fixed joint to take the TCP from", field="tcp")
        tcp = fixed[-1].name
    return robot.tool_transform(chain_transform(tool_urdf, tcp))


def tcp_waypoint_poses(route: Any, poses: Any) -> NDArray[np.float64]:
    """``(m, 4, 4)`` mm: the TCP pose at every route waypoint (NaN where there is none)."""
    from weldplan.tool.poses.route_frames import waypoint_quaternions

    pts = route.waypoints()
    quat = waypoint_quaternions(route, poses)
    T = np.full((len(pts), 4, 4), np.nan)
    has = np.all(np.isfinite(quat), axis=1)
    T[has, :3, :3] = Rotation.from_quat(np.roll(quat[has], -1, axis=1)).as_matrix()
    T[:, :3, 3] = pts
    T[:, 3] = [0.0, 0.0, 0.0, 1.0]
    return T


def _waypoint_frames(
    route: Any, poses: Any, flange_tcp: ArrayLike, tcp_poses: ArrayLike | None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(F (4, 4), T_tcp (m, 4, 4), T_flange (m, 4, 4))``: the flange -> TCP transform and the
    TCP and flange frames at every waypoint (``tcp_poses`` given, or from the route's poses)."""
    F = np.asarray(flange_tcp, dtype=np.float64).reshape(4, 4)
    T_tcp = (
        tcp_waypoint_poses(route, poses)
        if tcp_poses is None
        else np.asarray(tcp_poses, dtype=np.float64).reshape(-1, 4, 4)
    )
    return F, T_tcp, T_tcp @ np.linalg.inv(F)


def _ik_stats(
    placement: Any,
    rb: Robot,
    q: NDArray[np.float64],
    exact: NDArray[np.bool_],
    row_status: NDArray,
    t_ik: float,
) -> dict[str, Any]:
    """The route's stats after IK and the branch choice (placement, manipulability, seconds,
    waypoints unsolved by reason)."""
    return {
        "placement": {
            "base_xyz_yaw": list(placement.xyz_yaw()),
            "searched": placement.searched,
            "candidates": placement.candidates,
        },
        # smallest manipulability (Robot.manipulability) over the solved waypoints
        "min_manipulability": float(rb.manipulability(q[exact]).min()) if exact.any() else None,
        "seconds_ik_configs": round(t_ik, 3),
        "waypoints": len(q),
        # waypoints whose joint vector is interpolated (no usable IK solution), by reason
        "waypoints_unsolved": {
            str(w): int(c)
            for w, c in zip(*np.unique(row_status[~exact], return_counts=True), strict=True)
        },
    }


def _check_fk(
    rb: Robot,
    q: NDArray[np.float64],
    exact: NDArray[np.bool_],
    T_fl: NDArray[np.float64],
    row: NDArray[np.int64],
    stats: dict[str, Any],
) -> None:
    """FK of every solved configuration against its pose, into ``stats``; a miss beyond
    :data:`POSE_TOL_MM` / :data:`POSE_TOL_DEG` is a bug, not bad input (:class:`PlanningError`)."""
    err_mm, err_deg = _pose_errors(rb, q, exact, T_fl, row)
    stats["fk_max_error_mm"] = err_mm
    stats["fk_max_error_deg"] = err_deg
    if err_mm > POSE_TOL_MM or err_deg > POSE_TOL_DEG:
        raise PlanningError(
            f"FK of the chosen configurations misses the route poses by {err_mm:.3g} mm, "
            f"{err_deg:.3g} deg"
        )


def plan_robot_route(
    route: Any,
    poses: Any,
    robot: Robot,
    *,
    tool: ToolOnRobot,
    cell: RobotCell | None = None,
    settings: JointRouteSettings | None = None,
    rng: int | None = 0,
    tcp_poses: ArrayLike | None = None,
    zone: ArrayLike | None = None,
    exits: dict[int, tuple[NDArray[np.float64], ...]] | None = None,
) -> RobotRoute:
    """The route in joint space, verified (module docstring).

    Parameters
    ----------
    route, poses
        The route (:class:`~weldplan.weld.route.Route`) and its weld poses
        (:class:`~weldplan.tool.poses.WeldPoses`, one per visited weld in route order).
    robot
        The robot (:func:`~weldplan.robot.model.load_robot`).
    tool
        The tool on the flange (:class:`~weldplan.robot.settings.ToolOnRobot`: the flange ->
        TCP transform, :func:`tool_flange_tcp`; the tool mesh for the collision check, else only
        the links are checked).
    cell
        Where the robot works (:class:`~weldplan.robot.settings.RobotCell`: the part, the base
        given or searched, the floor); the part is required for the collision check. Default:
        no part, the robot's own base.
    settings
        :class:`~weldplan.robot.settings.JointRouteSettings` (default: its defaults).
    rng
        Seed of the OMPL detours and of the roadmaps.
    tcp_poses
        ``(m, 4, 4)`` mm: the TCP pose at every route waypoint (default: the weld poses, slerped
        between them by arc length); a route along the gun's transitions gives their own
        (:mod:`weldplan.robot.route.gunpath`).
    zone
        ``(m - 1,) bool``: the route's own motions on which the tool's contact zone is exempt
        (default: every one, the TCP is on the verified point-tip route); the others are checked
        with the whole tool.
    exits
        Per route row of a weld, TCP paths ``(k, 4, 4)`` mm leaving it that the tool stage
        proved free (:attr:`weldplan.robot.route.GunRoute.exits`): a detour leaves and reaches
        the weld along them before it tries its own retracts.

    Raises
    ------
    InputError
        The robot reaches none of the route's poses from the given base (field
        ``--robot-base``).
    PlanningError
        The robot reaches none of them from the searched base.
    ConfigError
        A collision check without a part (bad settings are refused when they are built).
    """
    t0 = time.perf_counter()
    s = JointRouteSettings() if settings is None else settings
    c = RobotCell() if cell is None else cell
    if s.check_collision and c.part is None:
        raise ConfigError("the collision check needs the part mesh", field="part")
    F, T_tcp, T_fl = _waypoint_frames(route, poses, tool.flange_tcp, tcp_poses)
    own_zone = _own_zone(zone, len(T_tcp))
    from weldplan.tool.poses.route_frames import weld_rows

    rows = weld_rows(route)
    zone_r = _contact_radius(s.contact_radius, poses)
    floor_z = cell_floor(c.search, c.base) if c.floor_z is None else c.floor_z
    checker = (
        RobotCollision(robot, c.part, tool.tool, F, contact_radius=zone_r, floor_z=floor_z)
        if s.check_collision
        else None
    )
    checker_for = None if checker is None else checker.with_robot
    placement, mask = place(robot, T_fl, rows, c.part, c.base, c.search, checker_for, s.placement)
    rb = robot.with_base(placement.base)
    if checker is not None:
        checker = checker.with_robot(rb)
    q, branch, exact, row_status, detail = _joint_route(
        rb, checker, T_fl, rows, mask, placement, s.singular_deg, s.flip_penalty
    )
    status = [str(row_status[r]) for r in rows]
    stats = _ik_stats(placement, rb, q, exact, row_status, time.perf_counter() - t0)
    stats["floor_z"] = floor_z
    path = _JointPath(q, np.arange(len(q), dtype=np.int64), exact, branch, ())
    det = None
    if checker is not None:
        det = Detour(
            rb, checker, T_tcp, F, s.singular_deg, s.planner, s.replan_time_s, rng,
            exits=exits or {},
            roadmap=_leg_roadmap(s.roadmap, placement, q[rows], tuple(route.order), rng),
        )  # fmt: skip
        path = _collision_stage(
            det, path, rows, status, detail, tuple(route.order), stats,
            replan=s.replan, zone=own_zone,
        )  # fmt: skip
        _roadmap_stats(det, placement, stats)
    if s.home is not None:
        from weldplan.robot.route.home import with_home

        welds = (rows, status, detail, tuple(route.order))
        path = with_home(det, rb, path, np.asarray(s.home), welds, stats)
    _check_fk(rb, path.q, path.exact, T_fl, path.row, stats)
    stats["seconds_total"] = round(time.perf_counter() - t0, 3)
    return _robot_route(robot, placement.base, F, path, rows, route.order, status, detail, stats)


@dataclass(frozen=True, eq=False)
class _JointPath:
    """The joint route as the stages hand it on: ``q (k, 6)`` rad, the route row of each joint
    row ``row (k,)``, ``exact (k,)`` (on the route's pose), the IK branch ``branch (k,)`` (-1:
    interpolated), and the legs re-planned in joint space."""

    q: NDArray[np.float64]
    row: NDArray[np.int64]
    exact: NDArray[np.bool_]
    branch: NDArray[np.int64]
    replanned: tuple[int, ...]


def _leg_roadmap(
    settings: RoadmapSettings | None,
    placement: Placement,
    q_weld: NDArray[np.float64],
    ids: tuple[str, ...],
    rng: int | None,
) -> LegRoadmap | None:
    """The detours' roadmaps at the chosen base (the base search's, when it built one there)."""
    if settings is None:
        return None
    wj = placement.join
    built = {wj.branch: wj.roadmap} if wj is not None and wj.roadmap is not None else None
    return LegRoadmap(q_weld, ids, settings, rng, built)


def _roadmap_stats(det: Detour, placement: Placement, stats: dict[str, Any]) -> None:
    """The roadmaps' figures into ``stats["roadmap"]`` (the legs asked, joined, the causes of
    those not joined, each branch's roadmap) and the base search's joins into
    ``stats["placement"]["joins"]``."""
    if placement.join is not None:
        stats["placement"]["joins"] = placement.join.summary()
    if det.roadmap is None:
        return
    det.roadmap.close()  # the route is assembled: no more queries
    stats["roadmap"] = {
        "legs": int(det.ompl.get("roadmap_legs", 0)),
        "joined": int(det.ompl.get("roadmap_joined", 0)),
        "not_joined": list(det.roadmap_misses),
        "maps": {str(b): dataclasses.asdict(m.report()) for b, m in det.roadmap.maps.items()},
    }


def _robot_route(
    robot: Robot,
    base: NDArray,
    F: NDArray,
    path: _JointPath,
    rows: NDArray,
    order: Any,
    status: list[str],
    detail: list[str],
    stats: dict[str, Any],
) -> RobotRoute:
    """The :class:`RobotRoute` of an assembled joint route: each weld's exact row, the branch
    flips (rows whose solved branch differs from the previous solved row's), logged."""
    q, row, exact, branch, replanned = path.q, path.row, path.exact, path.branch, path.replanned
    weld_index = np.array([_weld_row(row, exact, r) for r in rows], dtype=np.int64)
    solved = branch >= 0
    flips = [
        int(i)
        for i in range(1, len(q))
        if solved[i] and solved[i - 1] and branch[i] != branch[i - 1]
    ]
    rr = RobotRoute(
        robot=robot.name,
        joint_names=robot.joint_names,
        base=base,
        flange_tcp=F,
        q=q,
        row=row,
        exact=exact,
        branch=branch,
        weld_ids=tuple(order),
        weld_index=weld_index,
        status=tuple(status),
        flips=tuple(flips),
        replanned=tuple(replanned),
        stats=stats,
        detail=tuple(detail),
    )
    log.info(
        "robot route: %d/%d welds ok, %d flips, %d legs re-planned, %.1f s",
        rr.n_ok,
        len(status),
        len(flips),
        len(replanned),
        stats["seconds_total"],
    )
    return rr


def _collision_stage(
    det: Detour,
    path: _JointPath,
    rows: NDArray,
    status: list[str],
    detail: list[str],
    ids: tuple[str, ...],
    stats: dict[str, Any],
    *,
    replan: bool,
    zone: NDArray[np.bool_],
) -> _JointPath:
    """Check the joint path (``zone``: the motions whose contact zone is exempt), detour blocked
    legs (:func:`weldplan.robot.route.assemble`), check the final path again; welds charged with
    a remaining blocked motion get :data:`COLLISION` in ``status`` (in place), and the figures go
    to ``stats``."""
    q, row, exact, branch = path.q, path.row, path.exact, path.branch
    t1 = time.perf_counter()
    hits = det.checker.path_hits(q, zone)
    stats["first_check_hits"] = len(hits)
    stats["first_check_bodies"] = sorted({h.body for h in hits})
    replanned: list[int] = []
    if hits and replan:
        got = assemble(
            det, q, exact, branch, rows, status, detail, ids, zone=zone,
            blocked={h.segment for h in hits},
        )  # fmt: skip
        q, row, exact, branch, zone = got.q, got.row, got.exact, got.branch, got.zone
        replanned = list(got.replanned)
        hits = det.checker.path_hits(q, zone)  # the verification of the final path
        stats["ompl"] = dict(det.ompl)  # joint-space transfers: runs, retries, solved, s
        stats["detour_ends"] = dict(det.left_by)  # welds left/reached by a gun exit, a retract
        stats["walk"] = got.stats.to_dict()  # the walk's work, the welds it left out and why
    for h in hits:
        k = _blamed_weld(h, row, rows)
        if k is not None and status[k] == OK:
            status[k] = COLLISION
            detail[k] = f"{h.body} on the motion at joint row {h.segment} (not re-planned)"
    # the motions checked with the whole tool (the contact zone not exempt): verify --robot
    # checks them the same way (weldplan.robot.program.routejson)
    stats["whole_tool_motions"] = [int(i) for i in np.flatnonzero(~zone)]
    stats["seconds_collision"] = round(time.perf_counter() - t1, 3)
    stats["collision_free"] = not hits
    stats["hits"] = [
        {
            "segment": int(h.segment),
            "t": round(float(h.t), 4),
            "body": h.body,
            "distance": float(h.distance),
        }
        for h in hits
    ]
    return _JointPath(q, row, exact, branch, tuple(replanned))


def _joint_route(
    rb: Robot,
    checker: RobotCollision | None,
    T_fl: NDArray,
    rows: NDArray,
    mask: NDArray | None,
    placement: Placement,
    singular_deg: float,
    flip_penalty: float,
) -> tuple[NDArray, NDArray, NDArray, NDArray, list[str]]:
    """:func:`~weldplan.robot.route.joint_path` with, at the welds, only the branches free of
    the part (every usable branch checked, tool included, when there is a checker; else the
    search's mask); plus each weld's detail (the body blocking all its branches)."""
    detail = [""] * len(rows)
    if checker is not None:  # every usable branch of each weld pose, checked (tool included)
        mask, blame = free_branches(rb, checker, T_fl[rows], singular_deg)
        for k, b in enumerate(blame):
            if b is not None:
                detail[k] = f"{hit_words(b)} at the weld pose on every usable branch"
    allowed = None
    if mask is not None:
        allowed = np.ones((len(T_fl), 8), dtype=bool)
        allowed[rows] = mask
    try:
        q, branch, exact, row_status = joint_path(
            rb, T_fl, singular_deg=singular_deg, flip_penalty=flip_penalty, allowed=allowed
        )
    except PlanningError:
        if checker is not None and any(detail):
            raise PlanningError(
                "every weld the robot reaches collides at its pose (first: "
                f"{next(d for d in detail if d)})"
            ) from None
        raise InputError(
            _nothing_reached(rb, T_fl, rows, placement, singular_deg), field="--robot-base"
        ) from None
    return q, branch, exact, row_status, detail


def _own_zone(zone: ArrayLike | None, m: int) -> NDArray[np.bool_]:
    """``(m - 1,) bool``: the route's own motions whose contact zone is exempt (default all)."""
    if zone is None:
        return np.ones(max(m - 1, 0), dtype=bool)
    z = np.asarray(zone, dtype=bool).reshape(-1)
    if len(z) != max(m - 1, 0):
        raise ConfigError(f"zone has {len(z)} motions, the route {max(m - 1, 0)}", field="zone")
    return z


def _contact_radius(contact_radius: float | None, poses: Any) -> float:
    if contact_radius is not None:
        return float(contact_radius)
    from weldplan.tool.poses.plan import DEFAULT_CONTACT_RADIUS

    return float(getattr(poses, "settings", {}).get("contact_radius", DEFAULT_CONTACT_RADIUS))


def _nothing_reached(
    rb: Robot, T_fl: NDArray, rows: NDArray, placement: Placement, singular_deg: float
) -> str:
    """One line: no weld reached from the base, with the count of each reason."""
    has = np.all(np.isfinite(T_fl[rows]), axis=(1, 2))
    st = classify(rb.ik_all(np.where(has[:, None, None], T_fl[rows], np.eye(4))), singular_deg)
    st[~has] = NO_POSE
    words, counts = np.unique(st, return_counts=True)
    why = ", ".join(f"{c} {w.replace('_', ' ')}" for w, c in zip(words, counts, strict=True))
    x, y, z, yaw = placement.xyz_yaw()
    return (
        f"the robot reaches none of the {len(rows)} welds from its base at "
        f"{x:.0f},{y:.0f},{z:.0f},{yaw:.1f} ({why})"
    )


def _weld_row(row: NDArray[np.int64], exact: NDArray[np.bool_], r: int) -> int:
    """The joint row of route row ``r``: its exact one, else the first labelled ``r``."""
    on = np.flatnonzero(row == r)
    at = on[exact[on]]
    return int(at[0] if len(at) else on[0])


def _pose_errors(
    robot: Robot, q: NDArray, exact: NDArray, T_fl: NDArray, row: NDArray
) -> tuple[float, float]:
    """Largest mm and deg between FK (URDF chain) of the exact rows and their route poses."""
    if not exact.any():
        return 0.0, 0.0
    A = robot.fk(q[exact])
    B = T_fl[row[exact]]
    dp = np.linalg.norm(A[:, :3, 3] - B[:, :3, 3], axis=1)
    R = np.swapaxes(A[:, :3, :3], 1, 2) @ B[:, :3, :3]
    ang = np.degrees(Rotation.from_matrix(R).magnitude())
    return float(dp.max()), float(ang.max())


def _blamed_weld(hit: Hit, row: NDArray[np.int64], rows: NDArray[np.int64]) -> int | None:
    """The weld a blocked motion is charged to: the weld it leaves or reaches when it has one as
    an end (the nearer end when both), else the weld its leg leads to."""
    end = min(hit.segment + 1, len(row) - 1)  # a one-row path: its row blocked where it stands
    a, b = int(row[hit.segment]), int(row[end])
    at_a, at_b = np.flatnonzero(rows == a), np.flatnonzero(rows == b)
    if len(at_a) and (hit.t <= 0.5 or not len(at_b)):
        return int(at_a[0])
    if len(at_b):
        return int(at_b[0])
    k = int(np.searchsorted(rows, b, side="left"))
    return k if k < len(rows) else None
