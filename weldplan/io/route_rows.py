"""A route as waypoint rows, in travel order: what the route CSV and the robot posts write.

:func:`route_rows` gives one row per waypoint (``step``, ``kind``, ``joint_id``, ``x, y, z`` in
mm, ``tool``: the joint's approach direction on weld rows); the layout of the CSV written from
them is :mod:`weldplan.io.export`'s. :func:`travel_route` is the route whose waypoints are the
rows with the smooth paths (``route_rows(route, smooth=True)``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.weld.route import Route

#: decimals written for coordinates (mm) and unit directions
MM_DECIMALS = 4
DIR_DECIMALS = 6


def route_rows(route: Route, smooth: bool = False) -> list[dict[str, Any]]:
    """The route as waypoint rows (see the module docstring), in travel order.

    Weld spots shared by consecutive legs appear once. ``smooth=True``: the legs' smooth paths
    where they have one (rows of kind ``smooth`` between the virtual joints), as the exports
    write them; False (default): the polylines, the rows of :meth:`Route.waypoints`.
    """
    rows: list[dict[str, Any]] = []

    def add(kind: str, joint_id: str, p: NDArray[np.float64]) -> None:
        d = None
        if kind == "weld" and route.directions is not None:
            d = route.directions[route.index_of(joint_id)]
        rows.append(
            {
                "step": len(rows),
                "kind": kind,
                "joint_id": joint_id if kind == "weld" else "",
                "x": float(p[0]),
                "y": float(p[1]),
                "z": float(p[2]),
                "tool": None if d is None or not np.all(np.isfinite(d)) else d,
            }
        )

    if not route.legs:
        for jid in route.order:
            add("weld", jid, route.joint_xyz[route.index_of(jid)])
        return rows
    first = route.legs[0]
    add("weld", first.from_id, first.points[0])
    for leg in route.legs:
        vias = leg.points[1:-1]
        for p in (leg.path if smooth else leg.points)[1:-1]:
            on_polyline = leg.smooth is None or not smooth or bool(np.all(vias == p, axis=1).any())
            add("via" if on_polyline else "smooth", "", p)
        add("weld", leg.to_id, leg.points[-1])
    return rows


def travel_route(route: Route) -> Route:
    """``route`` with each leg's polyline replaced by its :attr:`~weldplan.weld.route.Leg.path`
    (its smooth path where it has one): the route whose :meth:`Route.waypoints` are the rows of
    ``route_rows(route, smooth=True)``. ``route`` itself when no leg is smoothed."""
    if not route.has_smooth:
        return route
    import dataclasses

    legs = tuple(
        dataclasses.replace(leg, points=leg.path, smooth=None, length=float("nan"))
        for leg in route.legs
    )
    return dataclasses.replace(route, legs=legs)


def fixed(v: float, decimals: int) -> str:
    """Fixed-point text without a negative zero."""
    return f"{round(float(v), decimals) + 0.0:.{decimals}f}"
