"""The robot route in the route JSON, and its re-check by ``weldplan verify``.

``weldplan plan --robot ... --json F`` writes the joint route the program was built from into the
route's tool section (its ``robot`` key, :attr:`weldplan.robot.program.ToolRoute.robot`:
:meth:`~weldplan.robot.route.RobotRoute.to_dict` with per waypoint row ``q``, ``row``,
``exact``, ``branch``; per weld ``weld_ids``, ``status`` and ``weld_branch``; plus the robot file
and its sha256, the contact radius of the check; and, when the robot followed the gun's
transitions, ``follows``: that route, its TCP orientations per waypoint, the motions whose
contact zone was exempt, how each leg goes: :meth:`weldplan.robot.route.GunRoute.to_dict`; the
robot route's rows are then its rows). :func:`weldplan.io.export.read_route` reads it back with
the rest of the route; this module reads it typed, once per route
(:meth:`weldplan.robot.program.ToolRoute.of`), and :func:`robot_route_of` checks the
:class:`~weldplan.robot.route.RobotRoute` in it.

:func:`verify_robot_route` re-checks it with nothing from the planner but the joint values:
forward kinematics of the URDF chain at every exact row puts the TCP on its route waypoint,
turned as the route's weld poses say (slerped between welds; :data:`FK_TOLERANCE_MM`,
:data:`FK_TOLERANCE_DEG`; a robot that followed the gun's transitions: on the route it followed,
which must weld the route's welds with a pose, each at its spot and pose), every row is inside
the joint limits, and the robot's links plus the tool are checked against the part along every
joint-space motion
(:class:`weldplan.robot.collision.RobotCollision`, the same proof the robot route was verified
with: the contact zone about the TCP exempt, as the weld poses were verified), against each other
(self-collision, the whole tool) and against the floor the route names (``stats["floor_z"]``:
the searched base's floor; a route without one is not checked against a floor, and the report
says so). It also finds, from the joint rows alone, the welds of the route the robot followed
that no exact row welds (:attr:`RobotCheck.left_out`): ``weldplan verify`` then exits 3, as
``plan`` did.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np

from weldplan.errors import InputError
from weldplan.geometry.checker import CheckVerdict

log = logging.getLogger(__name__)

#: mm and deg: FK of an exact row must put the TCP this close to its route waypoint's pose
FK_TOLERANCE_MM = 0.01
FK_TOLERANCE_DEG = 0.01
#: rad of slack on the joint limits (float round trip through JSON)
LIMIT_SLACK_RAD = 1e-9


def attach_robot_route(
    route: Any,
    rr: Any,
    *,
    urdf: str | PathLike[str],
    contact_radius: float | None = None,
    gun: Any = None,
) -> Any:
    """``route`` with ``rr`` (a :class:`~weldplan.robot.route.RobotRoute`) in its tool
    section's ``robot`` (module docstring). ``gun``: the route along the gun's transitions
    the robot followed (:class:`~weldplan.robot.route.GunRoute`), stored as ``follows``; the
    robot route's rows are then rows of that route."""
    from weldplan.io.mesh import file_sha256
    from weldplan.robot.program.toolroute import FollowedRoute, SavedRobotRoute, ToolRoute

    follows = None
    if gun is not None:
        follows = FollowedRoute(gun.route, gun.quaternions(), gun.zone, tuple(gun.via))
    saved = SavedRobotRoute(rr, str(urdf), file_sha256(urdf), contact_radius, follows)
    return dataclasses.replace(ToolRoute.of(route), robot=saved).on(route)


def saved_robot_route(route: Any, path: str | PathLike[str] | None = None) -> Any:
    """The robot section of ``route`` (:class:`~weldplan.robot.program.SavedRobotRoute`),
    ``None`` without one; :class:`InputError` (naming ``path``) when it is not readable."""
    return tool_route(route, path).robot


def tool_route(route: Any, path: str | PathLike[str] | None = None) -> Any:
    """``route``'s :class:`~weldplan.robot.program.ToolRoute` (read once per route);
    :class:`InputError` naming ``path`` and the field when its tool section is not readable:
    ``tool`` (the tool stage's part) or ``tool.robot``."""
    from weldplan.robot.program.toolroute import ToolRoute
    from weldplan.tool.section import ToolSection

    try:
        ToolSection.of(route)
    except (KeyError, TypeError, ValueError) as exc:
        why = f"the tool section is not valid ({exc})"
        raise InputError(why, path=path, field="tool") from None
    try:
        return ToolRoute.of(route)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(
            f"the robot route is not valid ({exc})", path=path, field="tool.robot"
        ) from None


def robot_route_of(route: Any, path: str | PathLike[str] | None = None) -> Any:
    """The :class:`~weldplan.robot.route.RobotRoute` a route carries, ``None`` without one.

    Raises
    ------
    InputError
        A robot section that is not a joint route (``path``: the route file, for the message).
    """
    saved = saved_robot_route(route, path)
    if saved is None:
        return None
    rr = saved.route
    k = len(rr.q)
    if not (len(rr.row) == len(rr.exact) == len(rr.branch) == k) or not np.all(np.isfinite(rr.q)):
        raise InputError(
            f"the robot route's rows do not match its {k} joint vectors (or are not finite)",
            path=path,
            field="tool.robot",
        )
    return rr


@dataclass(frozen=True)
class RobotCheck:
    """What :func:`verify_robot_route` found.

    Attributes
    ----------
    ok
        Every check passed.
    fk_mm, fk_deg
        Largest TCP distance (mm) and angle (deg) of an exact row's FK from its route pose.
    outside_limits
        Rows outside the joint limits.
    hits
        Blocked joint-space motions (``(segment, body, distance mm)``).
    rows
        Joint rows checked.
    floor_z
        mm: the floor the links and the tool were checked against (``None``: the route names
        none, e.g. a given base; not checked).
    left_out
        The welds of the route the robot followed that no exact row welds (the program passes
        them without welding): found from the rows, whatever the route's statuses say.
    """

    ok: bool
    fk_mm: float
    fk_deg: float
    outside_limits: tuple[int, ...]
    hits: tuple[tuple[int, str, float], ...]
    rows: int
    floor_z: float | None = None
    left_out: tuple[str, ...] = ()

    def describe(self) -> str:
        if self.ok and self.left_out:
            return f"{self._ok_words()}; {_left_out_words(self.left_out)}"
        if self.ok:
            return self._ok_words()
        parts = []
        if self.fk_mm > FK_TOLERANCE_MM or self.fk_deg > FK_TOLERANCE_DEG:
            parts.append(f"FK misses the route by {self.fk_mm:.3g} mm, {self.fk_deg:.3g} deg")
        if self.outside_limits:
            parts.append(f"rows {list(self.outside_limits[:5])} outside the joint limits")
        if self.hits:
            s, body, dist = self.hits[0]
            parts.append(f"{len(self.hits)} blocked motion(s), first: motion {s} ({body})")
        return "; ".join(parts)

    @property
    def verdict(self) -> CheckVerdict:
        """This check as a :class:`~weldplan.geometry.checker.CheckVerdict` (places: the FK,
        rows, motions; left out: the welds not in the program)."""
        from weldplan.robot.collision.selfcollision import hit_words

        fails = []
        if self.fk_mm > FK_TOLERANCE_MM or self.fk_deg > FK_TOLERANCE_DEG:
            fails.append(("FK", f"misses the route by {self.fk_mm:.3g} mm, {self.fk_deg:.3g} deg"))
        fails += [(f"row {r}", "outside the joint limits") for r in self.outside_limits]
        fails += [(f"motion {s}", f"{hit_words(b)} ({d:.2f} mm)") for s, b, d in self.hits]
        return CheckVerdict.of("robot route", self.rows, fails, left_out=self.left_out, ok=self.ok)

    def _ok_words(self) -> str:
        z = self.floor_z
        floor = "no floor known" if z is None else f"above the floor at z {z:.0f} mm"
        return (
            f"{self.rows} joint rows: FK within {self.fk_mm:.2g} mm, {self.fk_deg:.2g} deg of "
            "the route, inside the limits, robot + tool collision-free (part, self-collision; "
            f"{floor})"
        )


def _left_out_words(ids: tuple[str, ...]) -> str:
    more = f" and {len(ids) - 10} more" if len(ids) > 10 else ""
    return f"{len(ids)} weld(s) not in the program: {', '.join(ids[:10])}{more}"


def verify_robot_route(
    route: Any, rr: Any, robot: Any, part: Any, tool: Any, *, contact_radius: float | None = None
) -> RobotCheck:
    """Re-check the robot route ``rr`` of ``route`` (module docstring).

    Parameters
    ----------
    robot
        :class:`~weldplan.robot.model.Robot` (its base is taken from ``rr``).
    part
        The part mesh (mm).
    tool
        The :class:`~weldplan.tool.model.Tool` (mesh in its TCP frame), or None (links only).
    contact_radius
        mm: the tool's contact zone exempt (default: the value stored, else the poses').
    """
    from weldplan.robot.collision.checker import RobotCollision

    rb = robot.with_base(rr.base)
    follows = _followed(route)
    pts = route.waypoints() if follows is None else follows[0]
    left_out = _left_out(route if follows is None else follows[2], rr)
    if len(rr.row) and (rr.row.min() < 0 or rr.row.max() >= len(pts)):
        raise InputError("the robot route's rows are not rows of the route", field="tool.robot")
    ex = np.asarray(rr.exact, dtype=bool)
    tcp = rb.fk(rr.q[ex]) @ rr.flange_tcp
    err = np.linalg.norm(tcp[:, :3, 3] - pts[rr.row[ex]], axis=1)
    fk_mm = float(err.max()) if len(err) else 0.0
    if follows is None:
        fk_deg = _angle_error(route, rr, tcp)
    else:
        fk_deg = _angle_between(tcp, follows[1][rr.row[ex]])
    inside = np.all(
        (rr.q >= rb.lower - LIMIT_SLACK_RAD) & (rr.q <= rb.upper + LIMIT_SLACK_RAD), axis=1
    )
    if contact_radius is None:
        saved = tool_route(route).robot
        stored = None if saved is None else saved.contact_radius
        contact_radius = stored if stored is not None else poses_contact_radius(route)
    floor = (rr.stats or {}).get("floor_z")
    checker = RobotCollision(
        rb, part, tool, rr.flange_tcp, contact_radius=float(contact_radius), floor_z=floor
    )
    zone = _zone(rr)
    hits = checker.path_hits(rr.q, zone)
    ok = fk_mm <= FK_TOLERANCE_MM and fk_deg <= FK_TOLERANCE_DEG and bool(inside.all())
    ok = ok and not hits
    return RobotCheck(
        ok,
        fk_mm,
        fk_deg,
        tuple(int(i) for i in np.flatnonzero(~inside)),
        tuple((int(h.segment), str(h.body), float(h.distance)) for h in hits),
        len(rr.q),
        None if floor is None else float(floor),
        left_out,
    )


def _left_out(followed: Any, rr: Any) -> tuple[str, ...]:
    """The welds of ``followed`` (the route the robot followed) on whose row no exact joint row
    is: the program passes them without welding."""
    from weldplan.tool.poses.route_frames import weld_rows

    welded = set(rr.row[np.asarray(rr.exact, dtype=bool)].tolist())
    return tuple(
        str(w) for w, r in zip(followed.order, weld_rows(followed), strict=True) if r not in welded
    )


def _zone(rr: Any) -> Any:
    """``(k - 1,) bool``: the motions checked with the contact zone exempt, as the robot route
    was checked: every one except those its planner says it checked with the whole tool
    (``stats["whole_tool_motions"]``, a route along the gun's transitions); those are checked so
    here too, so the re-check is never weaker than the planner's claim."""
    zone = np.ones(max(len(rr.q) - 1, 0), dtype=bool)
    whole = np.asarray((rr.stats or {}).get("whole_tool_motions") or [], dtype=np.int64)
    if len(whole) and (whole.min() < 0 or whole.max() >= len(zone)):
        raise InputError(
            "the robot route's whole-tool motions are not its motions", field="tool.robot"
        )
    zone[whole] = False
    return zone


def _followed(route: Any) -> tuple[Any, Any, Any] | None:
    """``(points (m, 3) mm, quaternions (m, 4), the route)`` of the route along the gun's
    transitions the robot followed (``follows``), ``None`` when it followed the point-tip
    route.

    Raises
    ------
    InputError
        When that route does not weld exactly the route's welds that have a pose, each at its
        spot with its pose's orientation (1e-6 mm, 1e-6 of a quaternion component): the robot
        must weld at the verified poses, whatever it did between them.
    """
    from weldplan.tool.poses.route_frames import route_poses, weld_rows

    saved = tool_route(route).robot
    if saved is None or saved.follows is None:
        return None
    fr, Q = saved.follows.route, saved.follows.quaternions
    pts = fr.waypoints()
    poses = route_poses(route)
    want = [p for p in (poses.poses if poses else ()) if p.ok]
    rows = weld_rows(fr)
    good = len(Q) == len(pts) and sorted(fr.order) == sorted(p.id for p in want)
    for p in want if good else ():
        r = rows[fr.order.index(p.id)]
        q = np.asarray(p.quaternion)
        good &= bool(np.linalg.norm(pts[r] - np.asarray(p.position)) <= 1e-6)
        good &= bool(min(np.abs(Q[r] - q).max(), np.abs(Q[r] + q).max()) <= 1e-6)
    if not good:
        raise InputError(
            "the robot's route does not weld the route's welds at their poses", field="tool.robot"
        )
    return pts, Q, fr


def _angle_between(tcp: Any, quats: Any) -> float:
    """deg: the largest angle between the frames ``tcp (e, 4, 4)`` and ``quats (e, 4)``."""
    from scipy.spatial.transform import Rotation

    if not len(tcp):
        return 0.0
    R = Rotation.from_quat(np.roll(np.asarray(quats), -1, axis=1)).as_matrix()
    D = np.swapaxes(tcp[:, :3, :3], 1, 2) @ R
    return float(np.degrees(Rotation.from_matrix(D).magnitude()).max())


def poses_contact_radius(route: Any) -> float:
    """mm: the contact radius the route's weld poses were verified with
    (:data:`~weldplan.tool.poses.DEFAULT_CONTACT_RADIUS` without poses, or when they name
    none)."""
    from weldplan.tool.poses.plan import DEFAULT_CONTACT_RADIUS
    from weldplan.tool.section import ToolSection

    poses = ToolSection.of(route).poses
    settings = {} if poses is None else poses.settings
    return float((settings or {}).get("contact_radius", DEFAULT_CONTACT_RADIUS))


def _angle_error(route: Any, rr: Any, tcp: Any) -> float:
    """deg: the largest angle between the exact rows' TCP frames ``tcp (e, 4, 4)`` and the
    route's TCP orientation at their rows (none without weld poses)."""
    from scipy.spatial.transform import Rotation

    from weldplan.robot.route.plan import tcp_waypoint_poses
    from weldplan.tool.poses.route_frames import route_poses

    poses = route_poses(route)
    if poses is None or not len(tcp):
        return 0.0
    T = tcp_waypoint_poses(route, poses)[rr.row[np.asarray(rr.exact, dtype=bool)]]
    has = np.all(np.isfinite(T), axis=(1, 2))
    if not has.any():
        return 0.0
    R = np.swapaxes(tcp[has, :3, :3], 1, 2) @ T[has, :3, :3]
    return float(np.degrees(Rotation.from_matrix(R).magnitude()).max())
