"""The robot stages of a station: reach test, joint route, timing and program (docs/robot.md).

With a robot (and its tool: the tool's mounting frame on the robot's flange,
:class:`~weldplan.station.mount.MountedTool`), a plan

1. chooses the weld poses with the robot's reach test (:func:`reach_test`, from the base given
   or searched on the poses chosen without it, then kept: a gun pose the robot cannot take on a
   usable branch with its links clear of the part gives way to the next least-rotation free
   pose; :mod:`weldplan.robot.placement.posechoice`);
2. plans the joint route (:func:`joint_route_stage`, :func:`weldplan.robot.route.plan_robot_route`:
   one continuous IK branch, robot + tool collision check, blocked legs re-planned in joint
   space). When the tool stage planned transitions, the robot follows them: the welds in the
   tool's order, each leg the gun's TCP path as Cartesian steps
   (:mod:`weldplan.robot.route.gunpath`). A path that still collides is an error; a weld the robot
   cannot serve is passed without welding and listed with its reason;
3. times it and builds the program (:func:`program_stage`,
   :func:`weldplan.robot.program.robot_program`: toppra under the URDF velocities x
   ``vel_scale`` and accelerations x ``acc_scale``, ``weld_time`` a spot).

With ``cost = "time"`` the sequencer orders the welds by the robot's time
(:func:`time_leg_cost`), so the robot's base is fixed before the order exists.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from weldplan.errors import PlanningError
from weldplan.station.model import RobotSettings, ToolSettings

if TYPE_CHECKING:
    from weldplan.robot.settings import JointRouteSettings, ProgramSettings, ToolOnRobot

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class RobotAcceptance:
    """The robot's side of the pose stage (:func:`reach_test`)."""

    #: the pose choice's acceptance test (:class:`weldplan.robot.placement.ReachTest`)
    accept: Any
    #: the robot at the base the test judges from
    robot: Any
    #: the base searched on the first-pass poses; None when it was fixed beforehand
    placement: Any = None
    #: s spent on the first-pass poses and the base search
    seconds: float = 0.0


@dataclass(frozen=True, eq=False)
class RobotResult:
    """The joint route stage: the :class:`~weldplan.robot.route.RobotRoute`, the gun route it
    follows (None: the point-tip route), the route followed, the robot at its base with the
    scaled limits the timing uses, the reach test (if any)."""

    robot_route: Any
    gun: Any
    follow: Any
    robot: Any
    reach: RobotAcceptance | None = None


def tool_on_robot(mounted: Any) -> ToolOnRobot:
    """The :class:`~weldplan.robot.settings.ToolOnRobot` of a
    :class:`~weldplan.station.mount.MountedTool` (its tool, flange -> TCP transform and load)."""
    from weldplan.robot.settings import ToolOnRobot

    return ToolOnRobot(mounted.flange_tcp, mounted.tool, mounted.mass, mounted.cog)


def route_settings(roadmap: bool, home_deg: Any = None) -> JointRouteSettings:
    """The joint route's :class:`~weldplan.robot.settings.JointRouteSettings` of a station's robot:
    the defaults, with the roadmaps' work (:data:`weldplan.robot.settings.ROADMAP`) when
    :attr:`RobotSettings.roadmap` asks for it, and the home (``home_deg``, degrees; ``None``:
    none). With :func:`program_settings`, the one place where the station's
    :class:`RobotSettings` maps onto the robot stages' settings."""
    from weldplan.robot.settings import ROADMAP, JointRouteSettings

    home = None if home_deg is None else tuple(math.radians(v) for v in home_deg)
    return JointRouteSettings(roadmap=ROADMAP if roadmap else None, home=home)


def program_settings(settings: RobotSettings, name: str) -> ProgramSettings:
    """The program's :class:`~weldplan.robot.settings.ProgramSettings` of a station's robot
    (``name``: the program's)."""
    from weldplan.robot.settings import ProgramSettings

    return ProgramSettings(
        moves=settings.moves, weld_time=settings.weld_time, tcp_speed=settings.tcp_speed,
        name=name, home=settings.home is not None,
    )  # fmt: skip


def time_leg_cost(cell: Any, mounted: Any, robot: Any, base_fixed: bool, **kw: Any) -> Any:
    """``(LegTimes, robot placed)`` for ``cost = "time"``
    (:func:`weldplan.robot.route.cell_leg_times`). ``kw``: ``settings`` (RobotSettings),
    ``tool`` (ToolSettings), ``floor_z``, ``search`` (BaseSearch)."""
    from weldplan.robot.route.legtime import cell_leg_times

    rs: RobotSettings = kw["settings"]
    ts: ToolSettings = kw["tool"]
    return cell_leg_times(
        cell, mounted.tool, robot, mounted.flange_tcp, weld_time=rs.weld_time,
        velocity_scale=rs.vel_scale, acceleration_scale=rs.acc_scale,
        search=None if base_fixed else kw["search"], cone=ts.cone,
        contact_radius=ts.contact_radius,
    )  # fmt: skip


def with_time_stats(route: Any, legs: Any, joint_ids: tuple[str, ...]) -> Any:
    """The route with :func:`weldplan.robot.route.time_stats` in ``stats["cost_time"]``."""
    from weldplan.robot.route.legtime import time_stats

    stats = dict(route.stats)
    stats["cost_time"] = time_stats(legs, joint_ids, route.order)
    return dataclasses.replace(route, stats=stats)


def reach_test(
    cell: Any, route: Any, mounted: Any, robot: Any, *, base_fixed: bool, **kw: Any
) -> RobotAcceptance | None:
    """The robot's reach test for the weld poses (step 1 of the module docstring), from the
    robot's base when ``base_fixed``, else the base searched for the poses chosen without the
    robot (:func:`weldplan.robot.placement.place_for_poses`). ``kw``: ``tool``
    (ToolSettings), ``floor_z``, ``search``. None (logged) when no base candidate serves a
    weld: the robot stage then searches as without the test."""
    from weldplan.robot.collision.checker import RobotCollision
    from weldplan.robot.placement.posechoice import ReachTest, place_for_poses
    from weldplan.station.toolstage import pose_settings
    from weldplan.tool import plan_weld_poses

    t0 = time.perf_counter()
    ts: ToolSettings = kw["tool"]
    F = mounted.flange_tcp
    checker = RobotCollision(  # the tool: the base search's transfer trial checks it on the legs
        robot, cell.part, mounted.tool, F, contact_radius=ts.contact_radius, floor_z=kw["floor_z"]
    )
    placement = None
    if not base_fixed:
        first = plan_weld_poses(cell, route, mounted.tool, pose_settings(ts))
        try:
            placement = place_for_poses(
                robot, route, first, tool_on_robot(mounted), cell.part, checker, kw["search"],
                settings=route_settings(kw.get("roadmap", False)).placement,
            )  # fmt: skip
        except PlanningError as exc:
            log.warning("robot reach test skipped: no base for the first-pass poses (%s)", exc)
            return None
        robot = robot.with_base(placement.base)
        _warn_splits(placement)
    test = ReachTest(robot, F, checker.with_robot(robot))
    return RobotAcceptance(test, robot, placement, time.perf_counter() - t0)


def _warn_splits(placement: Any) -> None:
    """Say at once which legs the transfer trial found split at the searched base
    (:attr:`weldplan.robot.placement.roadmaps.WeldJoin.splits`): the robot stage's detours will
    try them with the gun's exits and OMPL, and may not join them."""
    wj = placement.join
    if wj is None or not wj.splits:
        return
    x, y, z, yaw = placement.xyz_yaw()
    log.warning(
        "base (%.0f, %.0f, %.0f) yaw %.1f deg: %d of %d served welds joined in one group by free "
        "legs and straight or tucked transfers; split (left to the detours' gun exits and OMPL): "
        "%s",
        x, y, z, yaw, wj.n_joined, int((wj.group >= 0).sum()), "; ".join(wj.splits),
    )  # fmt: skip


def joint_route_stage(
    cell: Any, route: Any, mounted: Any, robot: Any, *, base_fixed: bool, **kw: Any
) -> RobotResult:
    """Step 2 of the module docstring. ``kw``: ``reach`` (:class:`RobotAcceptance` or None),
    ``settings`` (RobotSettings), ``floor_z``, ``search`` (BaseSearch), ``seed``. Raises
    :class:`PlanningError` when the robot serves no weld or its path still collides."""
    from weldplan.robot.route.plan import plan_robot_route
    from weldplan.robot.settings import RobotCell
    from weldplan.tool.poses.route_frames import route_poses

    reach: RobotAcceptance | None = kw["reach"]
    poses = route_poses(route)
    given = base_fixed or (reach is not None and reach.placement is not None)
    if reach is not None:
        robot = reach.robot
    gun = _gun_route(route, poses)  # None: the robot follows the point-tip route
    follow = route if gun is None else gun.route
    at = RobotCell(
        cell.part, base=robot.base if given else None, search=None if given else kw["search"],
        floor_z=kw["floor_z"],  # a given floor is checked whatever the base
    )  # fmt: skip
    rr = plan_robot_route(
        follow, poses if gun is None else gun.poses, robot, tool=tool_on_robot(mounted), cell=at,
        settings=route_settings(kw.get("roadmap", False), kw["settings"].home), rng=kw["seed"],
        tcp_poses=None if gun is None else gun.tcp, zone=None if gun is None else gun.zone,
        exits=None if gun is None else gun.exits,
    )  # fmt: skip
    if reach is not None and reach.placement is not None:  # searched, before the poses
        rr.stats["placement"].update(
            searched=True, candidates=reach.placement.candidates, on="first-pass poses"
        )
        if reach.placement.join is not None:  # the transfer trial at the chosen base
            rr.stats["placement"]["joins"] = reach.placement.join.summary()
        if reach.placement.verdicts:  # per base judged: the welds it leaves out and why
            rr.stats["placement"]["bases"] = [v.summary() for v in reach.placement.verdicts]
    if "ok" not in rr.status:
        raise PlanningError(f"{_none_served(rr)}; nothing written")
    if rr.stats.get("collision_free") is False:
        raise PlanningError(f"{_still_collides(rr)}; nothing written")
    rs: RobotSettings = kw["settings"]
    rb = dataclasses.replace(
        robot.with_base(rr.base),
        velocity=robot.velocity * rs.vel_scale,
        acceleration=robot.acceleration * rs.acc_scale,
    )
    return RobotResult(rr, gun, follow, rb, reach)


def program_stage(
    cell: Any, route: Any, mounted: Any, joint: RobotResult, settings: RobotSettings, name: str
) -> Any:
    """Step 3 of the module docstring: the :class:`~weldplan.robot.program.ProgramBuild`.
    Raises :class:`PlanningError` when it serves none of the welds."""
    from weldplan.robot.program.build import robot_program
    from weldplan.robot.program.routejson import poses_contact_radius

    rr = joint.robot_route
    build = robot_program(
        joint.follow, rr.q, joint.robot, tool_on_robot(mounted), part=cell, row=rr.row,
        exact=rr.exact, settings=program_settings(settings, name),
        contact_radius=poses_contact_radius(route),
    )  # fmt: skip
    if len(build.skipped) == len(rr.weld_ids):
        raise PlanningError(f"the robot serves none of the welds ({', '.join(rr.status)})")
    if getattr(cell, "part_pose", None) is not None:  # the work object carries the part pose
        prog = dataclasses.replace(build.program, part_pose=cell.part_pose.matrix)
        build = dataclasses.replace(build, program=prog)
    return build


def with_robot(route: Any, joint: RobotResult, urdf: Any) -> Any:
    """``route`` carrying the robot route (its tool section's ``robot``, for the route JSON)."""
    from weldplan.robot.program.routejson import attach_robot_route, poses_contact_radius

    return attach_robot_route(
        route, joint.robot_route, urdf=urdf, contact_radius=poses_contact_radius(route),
        gun=joint.gun,
    )  # fmt: skip


def _still_collides(rr: Any) -> str:
    hits = rr.stats.get("hits") or []
    first = (
        f"first: {hits[0]['body']} at motion {hits[0]['segment']}, t {hits[0]['t']:.2f}"
        if hits and isinstance(hits[0], dict) and "body" in hits[0]
        else f"first: {hits[0] if hits else '?'}"
    )
    return f"the robot route still collides after re-planning ({len(hits)} hit(s), {first})"


def _none_served(rr: Any) -> str:
    """One line: the robot serves no weld from its base, and why each was left out (the
    statuses counted, the first weld of each with its detail)."""
    from collections import Counter

    x, y, z = rr.base[:3, 3]
    yaw = math.degrees(math.atan2(rr.base[1, 0], rr.base[0, 0]))
    detail = dict(zip(rr.weld_ids, rr.detail or ("",) * len(rr.weld_ids), strict=True))
    first: dict[str, str] = {}
    for w, st in zip(rr.weld_ids, rr.status, strict=True):
        first.setdefault(st, w)

    def one(st: str, n: int) -> str:
        w = first[st]
        return f"{n} {st} (first weld {w}" + (f": {detail[w]})" if detail[w] else ")")

    why = "; ".join(one(st, n) for st, n in Counter(rr.status).most_common())
    return (
        f"the robot serves none of the {len(rr.weld_ids)} weld(s) with a tool pose from its base "
        f"({x:.0f}, {y:.0f}, {z:.0f}) mm, yaw {yaw:.1f} deg: {why}"
    )


def _gun_route(route: Any, poses: Any) -> Any:
    """The route along the tool stage's transitions, in its order
    (:func:`weldplan.robot.route.gun_route`); None when the route carries none."""
    from weldplan.robot.program.routejson import poses_contact_radius
    from weldplan.robot.route.gunpath import gun_route
    from weldplan.tool.poses.route_frames import route_tool_path

    path = route_tool_path(route)
    if path is None or not path.order:
        return None
    return gun_route(route, poses, path, contact_radius=poses_contact_radius(route))
