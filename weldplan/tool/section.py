"""The tool stage's part of a route's ``tool`` section, typed: :class:`ToolSection`.

A route planned with a tool carries, in its ``tool`` section (the route JSON's), the tool's
``provenance``, the weld ``poses`` (:class:`~weldplan.tool.poses.WeldPoses`) and the tool's
``transitions`` (:class:`~weldplan.tool.transitions.ToolPath`), and, with a robot, the robot's
route. :class:`ToolSection` reads the tool stage's three, as the readers of this layer need them
(the route's frames, the re-checks of a saved route, the exporters, the viewer), once per route
(:meth:`ToolSection.of`). The whole section with the robot's route is
:class:`weldplan.robot.program.ToolRoute`, which reads its first three keys here. The keys not
read here (``robot``, and any this version does not know) are kept as they were in
:attr:`ToolSection.rest`.

No module reads a route's ``tool`` section as a dict but these two views, and none writes one
but through them (:meth:`ToolSection.on`, :meth:`ToolRoute.on
<weldplan.robot.program.ToolRoute.on>`; ``tests/test_code_shape.py``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

from weldplan.tool.poses.result import WeldPoses
from weldplan.tool.transitions.result import ToolPath
from weldplan.weld.route import Route

_View = TypeVar("_View")

#: the keys of the tool section the tool stage writes, in the order it writes them
TOOL_STAGE_KEYS = ("provenance", "poses", "transitions")


@dataclass(frozen=True, eq=False)
class ToolSection:
    """The tool stage's results a route carries (module docstring).

    Attributes
    ----------
    provenance
        The tool the route was planned with (:func:`weldplan.tool.model.load_tool`: files and
        their sha256, the TCP, the units); metadata, compared, never computed on. Empty for a
        route planned without a tool.
    poses
        :class:`~weldplan.tool.poses.WeldPoses`, one per visited weld in the route's order
        (None: none saved).
    transitions
        :class:`~weldplan.tool.transitions.ToolPath` (None: the route was planned without them).
    rest
        The section's other keys (the robot's route, keys this version does not know), as read.
    """

    provenance: Mapping[str, Any] = field(default_factory=dict)
    poses: WeldPoses | None = None
    transitions: ToolPath | None = None
    rest: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> ToolSection:
        """Read a route's ``tool`` section (``{}`` or None: a point-tip route).

        Raises
        ------
        KeyError, TypeError, ValueError
            A section that is not what the planner writes (the caller names the file).
        """
        d = d or {}
        poses, path = d.get("poses"), d.get("transitions")
        return cls(
            provenance=dict(d.get("provenance") or {}),
            poses=WeldPoses.from_dict(poses) if poses else None,
            transitions=ToolPath.from_dict(path) if path else None,
            rest={k: v for k, v in d.items() if k not in TOOL_STAGE_KEYS},
        )

    def to_dict(self) -> dict[str, Any]:
        """The ``tool`` section in the planner's layout: ``provenance``, ``poses`` and
        ``transitions`` (where there are some), then :attr:`rest`; ``{}`` for an empty section
        (a point-tip route)."""
        d: dict[str, Any] = {}
        if self.provenance or self.poses is not None or self.transitions is not None:
            d["provenance"] = dict(self.provenance)
        if self.poses is not None:
            d["poses"] = self.poses.to_dict()
        if self.transitions is not None:
            d["transitions"] = self.transitions.to_dict()
        d.update(self.rest)
        return d

    def on(self, route: Route | Any) -> Any:
        """``route`` carrying this section in its ``tool`` (a new route, which reads its
        section again: :meth:`of`). The one way the tool stage writes a route's section
        (``tests/test_code_shape.py``); :class:`weldplan.robot.program.ToolRoute` writes the
        whole section with the robot's route the same way."""
        import dataclasses

        return dataclasses.replace(route, tool=self.to_dict())

    @classmethod
    def of(cls, route: Route | Any) -> ToolSection:
        """The tool section of a :class:`~weldplan.weld.route.Route` (its ``tool``), read once
        per route (:meth:`~weldplan.weld.route.Route.tool_view`): the readers of a route share
        one parse. Another object with a ``tool`` mapping is read each time.

        Raises
        ------
        KeyError, TypeError, ValueError
            As :meth:`from_dict` (nothing is cached then).
        """
        return cached_view(route, _read)


def cached_view(route: Any, read: Callable[[Any], _View]) -> _View:
    """``read(route)``, cached on ``route`` when it is a :class:`~weldplan.weld.route.Route`
    (:meth:`~weldplan.weld.route.Route.tool_view`); computed each time for another object
    with a ``tool`` mapping (a stand-in for a route)."""
    view = getattr(route, "tool_view", None)
    return read(route) if view is None else view(read)


def _read(route: Any) -> ToolSection:
    """The view :meth:`ToolSection.of` caches on a route."""
    return ToolSection.from_dict(route.tool)
