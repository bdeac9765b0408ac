"""The TCP orientation at every waypoint of a route that carries weld poses.

At a weld with a verified pose the orientation is that pose's. Between two welds it is the
spherical linear interpolation (:class:`scipy.spatial.transform.Slerp`) of their orientations,
parametrised by arc length along the route's polyline (approach segments and local-path vias
included). A weld without a free pose has no orientation of its own: its row is left empty, and
the waypoints around it are interpolated between the nearest welds before and after it that have
a pose. Before the first and after the last weld with a pose the orientation is held.

These orientations are IK targets along the point-tip route, not a verified transition: the
swept tool between welds is not checked here (issue 16, item 3), so no output file carries them
(the route CSV writes the weld poses only, :func:`weldplan.io.export.to_csv_text`; the verified
tool path is :mod:`weldplan.io.tool_csv`).
"""

from __future__ import annotations

import logging

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation, Slerp

from weldplan.tool.poses.result import WeldPoses
from weldplan.tool.section import ToolSection
from weldplan.tool.transitions.result import ToolPath
from weldplan.weld.route import Route

log = logging.getLogger(__name__)


def weld_rows(route: Route) -> NDArray[np.int64]:
    """``(len(route.order),)``: the row of each visited weld in :meth:`Route.waypoints`."""
    if not route.legs:
        return np.arange(len(route.order), dtype=np.int64)
    steps = [len(leg.points) - 1 for leg in route.legs]
    return np.concatenate([[0], np.cumsum(steps)]).astype(np.int64)


def route_poses(route: Route) -> WeldPoses | None:
    """The route's :class:`WeldPoses` (:attr:`ToolSection.poses
    <weldplan.tool.section.ToolSection.poses>`), ``None`` without a tool.

    Raises
    ------
    ValueError
        When the poses are not one per visited weld in the route's order (KeyError, TypeError
        or ValueError: a tool section that is not what the planner writes).
    """
    poses = ToolSection.of(route).poses
    if poses is None:
        return None
    if poses.order != route.order:
        raise ValueError(
            f"the route's weld poses are for {'-'.join(poses.order)}, "
            f"the route visits {'-'.join(route.order)}"
        )
    return poses


def route_tool_path(route: Route) -> ToolPath | None:
    """The route's :class:`~weldplan.tool.transitions.ToolPath` (:attr:`ToolSection.transitions
    <weldplan.tool.section.ToolSection.transitions>`), ``None`` without transitions."""
    return ToolSection.of(route).transitions


def waypoint_quaternions(route: Route, poses: WeldPoses) -> NDArray[np.float64]:
    """TCP orientation ``(qw, qx, qy, qz)`` at every waypoint (module docstring).

    Parameters
    ----------
    route
        The route; its waypoints are :meth:`Route.waypoints` (``(m, 3)`` mm).
    poses
        One pose per visited weld, in ``route.order``.

    Returns
    -------
    ``(m, 4) float``
        Unit quaternions, scalar first, ``qw >= 0``; NaN rows at welds without a pose, and
        everywhere when no weld has one.
    """
    pts = route.waypoints()
    m = len(pts)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    rows = weld_rows(route)
    ok = [i for i, p in enumerate(poses.poses) if p.ok and p.quaternion is not None]
    out = np.full((m, 4), np.nan)
    if not ok:
        return out
    key_s = s[rows[ok]]
    key_q = np.array([poses.poses[i].quaternion for i in ok], dtype=np.float64)
    key_s, first = np.unique(key_s, return_index=True)  # Slerp needs strictly increasing times
    key_q = key_q[first]
    if len(key_s) == 1:
        out[:] = key_q[0]
    else:
        rot = Rotation.from_quat(np.roll(key_q, -1, axis=1))  # scipy is scalar last
        q = Slerp(key_s, rot)(np.clip(s, key_s[0], key_s[-1])).as_quat()
        out = np.roll(q, 1, axis=1)
    out = np.where(out[:, :1] < 0, -out, out)
    for i, p in enumerate(poses.poses):  # exact at the welds; empty where there is no pose
        out[rows[i]] = np.nan if (not p.ok or p.quaternion is None) else p.quaternion
    return out
