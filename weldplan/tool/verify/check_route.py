"""``weldplan verify --tool``: re-check the weld poses a route JSON carries, with the given tool.

The route JSON records the tool it was planned with (:func:`weldplan.tool.model.load_tool`'s
provenance: file sha256, mesh sha256, TCP, units). :func:`check_tool_provenance` refuses a route
planned with another tool, or without one. :func:`verify_route_poses` then checks that the poses
belong to the route (one per visited weld, in its order, each at its weld spot) and re-checks every
pose reported ok with :func:`weldplan.tool.verify.verify_poses` (fresh FCL models of the
whole part and the whole tool, none of the search's caches). :func:`verify_route_sweeps`
re-checks the tool's transitions for the swept tool with
:func:`weldplan.tool.verify.verify_sweeps` (fresh FCL models, uniform samples and its own
bound). The route's tool section is read as a :class:`~weldplan.tool.section.ToolSection`.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np

from weldplan.errors import InputError
from weldplan.geometry.checker import CheckVerdict
from weldplan.tool.model.load import provenance_mismatch
from weldplan.tool.poses.result import NO_FREE_POSE, OK
from weldplan.tool.poses.route_frames import route_poses
from weldplan.tool.section import ToolSection
from weldplan.tool.verify.poses import verify_poses
from weldplan.weld.route import Route

log = logging.getLogger(__name__)

#: mm: a pose's position may differ from its weld spot by at most this (JSON round-off)
POSITION_TOL_MM = 1e-6


@dataclass(frozen=True)
class RoutePosesCheck:
    """Outcome of :func:`verify_route_poses`.

    ``ok``: every pose reported ok passed and the poses belong to the route; ``n_ok`` of
    ``n`` welds have a pose (the others are listed in ``missing``, reported by the planner with
    their closest miss: not a failure of the check, a partial route).
    """

    ok: bool
    n: int
    n_ok: int
    missing: tuple[str, ...] = ()
    failures: tuple[tuple[str, str], ...] = ()
    #: mm: the least distance measured of the tool outside its zone to the part (``nan``: none)
    min_clearance: float = math.nan

    @property
    def verdict(self) -> CheckVerdict:
        """This check as a :class:`~weldplan.geometry.checker.CheckVerdict` (places: welds;
        left out: the welds without a pose)."""
        return CheckVerdict.of(
            "tool poses", self.n_ok, self.failures, place="weld {}", ok=self.ok,
            min_clearance=self.min_clearance, left_out=self.missing,
        )  # fmt: skip

    def describe(self, limit: int = 20) -> str:
        if not self.ok:
            shown = "; ".join(f"weld {i}: {r}" for i, r in self.failures[:limit])
            more = len(self.failures) - limit
            return f"{len(self.failures)} failure(s): {shown}" + (
                f"; ... {more} more" if more > 0 else ""
            )
        text = f"{self.n_ok} / {self.n} welds with a free pose, each re-checked (fresh FCL models)"
        if self.missing:
            text += f"; without a pose (closest miss in the JSON): {', '.join(self.missing)}"
        return text


def check_tool_provenance(
    route: Route, given: dict[str, Any], path: str | PathLike[str] | None = None
) -> None:
    """Refuse a route planned without a tool or with another one, or whose tool section is
    unreadable (:class:`InputError`)."""
    try:
        section = ToolSection.of(route)
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"unreadable tool section: {exc}", path=path, field="tool") from exc
    if section.poses is None:
        raise InputError("the route was planned without --tool: no poses to check", path=path)
    diff = provenance_mismatch(dict(section.provenance), given)
    if diff:
        raise InputError(
            f"the route was planned with another tool: {'; '.join(diff)}",
            path=path,
            field="tool.provenance",
        )


def verify_route_poses(route: Route, part: Any, tool: Any) -> RoutePosesCheck:
    """Re-check the poses ``route.tool`` carries against ``part`` (trimesh, mm) with ``tool``."""
    failures: list[tuple[str, str]] = []
    try:
        poses = route_poses(route)
    except (KeyError, TypeError, ValueError) as exc:
        return RoutePosesCheck(False, 0, 0, failures=(("-", f"unreadable poses: {exc}"),))
    if poses is None:
        return RoutePosesCheck(False, 0, 0, failures=(("-", "the route carries no poses"),))
    for key in ("contact_radius", "clearance"):
        v = poses.settings.get(key)
        if not isinstance(v, (int, float)) or not (math.isfinite(v) and v >= 0):
            failures.append(("-", f"settings.{key} is {v!r}, not a finite number >= 0"))
    for wp in poses.poses:
        spot = route.joint_xyz[route.index_of(wp.id)]
        if np.max(np.abs(np.asarray(wp.position) - spot)) > POSITION_TOL_MM:
            failures.append((wp.id, f"pose at {list(wp.position)}, the weld spot is {list(spot)}"))
        if wp.status not in (OK, NO_FREE_POSE):
            failures.append((wp.id, f"unknown status {wp.status!r}"))
    if failures:
        return RoutePosesCheck(False, len(poses.poses), poses.n_ok, failures=tuple(failures))
    v = verify_poses(poses, part, tool)
    missing = tuple(p.id for p in poses.poses if not p.ok)
    return RoutePosesCheck(
        v.ok, len(poses.poses), poses.n_ok, missing, tuple(v.failures), v.min_clearance
    )


def verify_route_sweeps(route: Route, part: Any, tool: Any) -> Any:
    """Re-check the transitions ``route.tool`` carries (``None`` when it carries none).

    Returns a :class:`~weldplan.tool.verify.SweepsVerification`; an unreadable tool path
    is a failed one.
    """
    from weldplan.tool.verify.sweeps import SweepsVerification, verify_sweeps

    def unreadable(why: object) -> SweepsVerification:
        return SweepsVerification(False, 0, 0, failures=(("-", f"unreadable tool path: {why}"),))

    try:
        section = ToolSection.of(route)
    except (KeyError, TypeError, ValueError) as exc:
        return unreadable(exc)
    if section.transitions is None:
        return None
    if section.poses is None:
        return unreadable("the route carries transitions and no poses")
    return verify_sweeps(section.transitions, section.poses, part, tool)
