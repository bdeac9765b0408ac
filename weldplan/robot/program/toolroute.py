"""The route JSON's tool section as typed objects: :class:`ToolRoute`.

A route planned with a tool carries, in its ``tool`` section, what the tool and robot stages
added (docs/tool.md, docs/robot.md): the tool's ``provenance``, the weld ``poses``
(:class:`~weldplan.tool.poses.WeldPoses`), the tool's ``transitions``
(:class:`~weldplan.tool.transitions.ToolPath`) and, with a robot, the joint route
(:class:`SavedRobotRoute`: the :class:`~weldplan.robot.route.RobotRoute`, the robot file and its
sha256, the contact radius of the check, and the route along the gun's transitions it followed,
:class:`FollowedRoute`). :meth:`ToolRoute.from_dict` reads that section once, and
:meth:`ToolRoute.to_dict` writes it back in the same layout, key for key: the route JSON's format
is unchanged, so the files written before :class:`ToolRoute` existed still load, and a route
read and written again gives the same bytes (``tests/test_saved_plan.py``). The tool stage's
keys are read by :class:`weldplan.tool.section.ToolSection`, what the layers below the robot's
read; :meth:`ToolRoute.of` reads a route's section once, on that view's parse.

Keys this version does not know are kept as they were (``extra``), so a newer file is not
silently stripped when it is re-written.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: the keys of the tool section, in the order the planner writes them
TOOL_KEYS = ("provenance", "poses", "transitions", "robot")
#: the keys the robot section adds to :meth:`RobotRoute.to_dict`, in the planner's order
ROBOT_KEYS = ("weld_branch", "urdf", "urdf_sha256", "contact_radius", "follows")
#: the keys of the followed route (:meth:`weldplan.robot.route.GunRoute.to_dict`)
FOLLOWS_KEYS = ("route", "quaternions", "zone", "via")


def _extra(d: Mapping[str, Any], known: tuple[str, ...]) -> dict[str, Any]:
    return {k: v for k, v in d.items() if k not in known}


@dataclass(frozen=True, eq=False)
class FollowedRoute:
    """The route along the gun's transitions a robot followed, as saved.

    Attributes
    ----------
    route
        :class:`~weldplan.weld.route.Route` in the tool's order (leg ``k``: transition ``k``).
    quaternions
        ``(m, 4)``: the TCP orientation ``(qw, qx, qy, qz)`` at each of its waypoints.
    zone
        ``(m - 1,) bool``: the motions whose contact zone may be exempt.
    via
        Per leg, how the gun goes.
    extra
        Keys this version does not know, kept as read.
    """

    route: Any = field(repr=False)
    quaternions: NDArray[np.float64] = field(repr=False)
    zone: NDArray[np.bool_] = field(repr=False)
    via: tuple[str, ...]
    extra: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> FollowedRoute:
        from weldplan.weld.route import Route

        return cls(
            route=Route.from_dict(d["route"]),
            quaternions=np.asarray(d["quaternions"], dtype=np.float64).reshape(-1, 4),
            zone=np.asarray(d.get("zone", ()), dtype=bool),
            via=tuple(str(v) for v in d.get("via", ())),
            extra=_extra(d, FOLLOWS_KEYS),
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "route": self.route.to_dict(),
            "quaternions": self.quaternions.tolist(),
            "zone": self.zone.astype(int).tolist(),
            "via": list(self.via),
            **self.extra,
        }


@dataclass(frozen=True, eq=False)
class SavedRobotRoute:
    """The robot section of a saved route (:mod:`weldplan.robot.program.routejson`).

    Attributes
    ----------
    route
        The :class:`~weldplan.robot.route.RobotRoute` (joint rows, base, flange TCP, statuses).
    urdf, urdf_sha256
        The robot file the route was planned with, and its sha256.
    contact_radius
        mm: the contact zone about the TCP exempt in the robot's collision check (None: the
        poses' own).
    follows
        The route along the gun's transitions the robot followed (None: the point-tip route).
    extra
        Keys this version does not know, kept as read.
    """

    route: Any
    urdf: str | None = None
    urdf_sha256: str | None = None
    contact_radius: float | None = None
    follows: FollowedRoute | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> SavedRobotRoute:
        from weldplan.robot.route.configs import RobotRoute

        rr = RobotRoute.from_dict(d)
        known = tuple(rr.to_dict()) + ROBOT_KEYS
        f = d.get("follows")
        return cls(
            route=rr,
            urdf=d.get("urdf"),
            urdf_sha256=d.get("urdf_sha256"),
            contact_radius=d.get("contact_radius"),
            follows=FollowedRoute.from_dict(f) if f else None,
            extra=_extra(d, known),
        )

    def to_dict(self) -> dict[str, Any]:
        d = self.route.to_dict()
        d["weld_branch"] = self.route.weld_branch.tolist()
        d["urdf"] = self.urdf
        d["urdf_sha256"] = self.urdf_sha256
        d["contact_radius"] = self.contact_radius
        if self.follows is not None:
            d["follows"] = self.follows.to_dict()
        d.update(self.extra)
        return d


@dataclass(frozen=True, eq=False)
class ToolRoute:
    """What a route planned with a tool carries (module docstring).

    Attributes
    ----------
    provenance
        The tool the route was planned with (:func:`weldplan.tool.model.load_tool`: files and
        their sha256, the TCP, the units); metadata, compared, never computed on.
    poses
        :class:`~weldplan.tool.poses.WeldPoses`, one per visited weld in the route's order
        (None: none saved).
    transitions
        :class:`~weldplan.tool.transitions.ToolPath` (None: the route was planned without them).
    robot
        :class:`SavedRobotRoute` (None without a robot).
    extra
        Keys this version does not know, kept as read.
    """

    provenance: Mapping[str, Any] = field(default_factory=dict)
    poses: Any = None
    transitions: Any = None
    robot: SavedRobotRoute | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> ToolRoute:
        """Read a route's ``tool`` section (``{}`` or None: a point-tip route).

        Raises
        ------
        KeyError, TypeError, ValueError
            A section that is not what the planner writes (the caller names the file).
        """
        from weldplan.tool.section import ToolSection

        return cls.from_section(ToolSection.from_dict(d))

    @classmethod
    def from_section(cls, tool: Any) -> ToolRoute:
        """The whole section from its tool stage's part (a
        :class:`~weldplan.tool.section.ToolSection`, whose ``rest`` holds the robot's route and
        the keys this version does not know); the poses and the transitions are ``tool``'s own
        objects.

        Raises
        ------
        KeyError, TypeError, ValueError
            A robot section that is not what the planner writes.
        """
        robot = tool.rest.get("robot")
        return cls(
            provenance=tool.provenance,
            poses=tool.poses,
            transitions=tool.transitions,
            robot=SavedRobotRoute.from_dict(robot) if robot else None,
            extra=_extra(tool.rest, TOOL_KEYS),
        )

    def to_dict(self) -> dict[str, Any]:
        """The ``tool`` section, in the planner's layout (``{}`` for a point-tip route)."""
        d: dict[str, Any] = {}
        if self.provenance:
            d["provenance"] = dict(self.provenance)
        if self.poses is not None:
            d["poses"] = self.poses.to_dict()
        if self.transitions is not None:
            d["transitions"] = self.transitions.to_dict()
        if self.robot is not None:
            d["robot"] = self.robot.to_dict()
        d.update(self.extra)
        return d

    @classmethod
    def of(cls, route: Any) -> ToolRoute:
        """The tool section of a :class:`~weldplan.weld.route.Route`, read once per route
        (:meth:`~weldplan.weld.route.Route.tool_view`) on the route's
        :meth:`ToolSection.of <weldplan.tool.section.ToolSection.of>`: the poses and the
        transitions are parsed once for both views.

        Raises
        ------
        KeyError, TypeError, ValueError
            As :meth:`from_dict` (nothing is cached then).
        """
        from weldplan.tool.section import cached_view

        return cached_view(route, _read)

    @classmethod
    def from_json(cls, text: str) -> ToolRoute:
        return cls.from_dict(json.loads(text))

    def to_json(self, indent: int | None = 1) -> str:
        from weldplan.weld.route import _jsonable

        return json.dumps(_jsonable(self.to_dict()), indent=indent, allow_nan=False)

    def on(self, route: Any) -> Any:
        """``route`` carrying this section (a new Route)."""
        import dataclasses

        return dataclasses.replace(route, tool=self.to_dict())

    @property
    def is_empty(self) -> bool:
        return not self.to_dict()


def _read(route: Any) -> ToolRoute:
    """The view :meth:`ToolRoute.of` caches on a route."""
    from weldplan.tool.section import ToolSection

    return ToolRoute.from_section(ToolSection.of(route))
