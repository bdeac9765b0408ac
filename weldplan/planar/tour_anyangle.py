"""Any-angle leg costs of multi-goal tours: Polyanya between every pair of stops.

Paper 002 orders the targets over shortest paths along the edges of a triangular mesh
(:class:`~weldplan.planar.tour_order.TourGraph`); those lengths overestimate the true shortest
paths by the mesh's zig-zag, so the order that is optimal over them need not be the shortest
tour. :func:`build_anyangle_graph` instead asks Polyanya (Cui, Harabor & Grastien, IJCAI 2017,
:class:`~weldplan.planar.polyanya.Polyanya`) for the exact any-angle shortest path between
every pair of stops, ``k (k - 1) / 2`` queries for ``k`` stops (the paths are symmetric; the
public API answers one start-goal pair per query), on the navigation mesh of the tour's map:

* a scenario map: :func:`~weldplan.planar.anyangle.scenario_navmesh` (circles as the
  circumscribed polygons of the visibility graph, so the legs clear the true circles and are at
  most about ``(pi / n)^2 / 3`` longer on arcs);
* a map that is only an occupancy grid filling its bounds (the house floorplan):
  :func:`~weldplan.planar.navmesh.grid_navmesh` in cell units, stops mapped into it and the
  lengths scaled back by the cell size;
* a Polyanya ``.mesh`` task (:func:`~weldplan.planar.tour_scenarios.navmesh_tour`): the mesh itself.

Held-Karp over the resulting ``dist`` is then the exact optimal tour through the stops (any
angle), which is what every tour's gap is measured against.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import PlanningError
from weldplan.planar.navmesh import NavMesh
from weldplan.planar.polyanya import Polyanya

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class AnyAngleTourGraph:
    """Exact any-angle shortest paths between the stops (start first, then goals).

    Attributes
    ----------
    mesh
        The navigation mesh that was searched (in cell units on a grid map, see ``scale``).
    dist
        ``(t + 1, t + 1)``: shortest any-angle path lengths (map units), symmetric, zero
        diagonal.
    legs
        ``{(a, b): (p, 2)}`` for ``a < b``: Polyanya's path from stop ``a`` to stop ``b`` (map
        units), start and goal included.
    build_seconds
        Time to build the mesh and to answer every query; ``mesh_seconds`` the mesh alone.
    n_queries, expanded
        Polyanya queries run and search nodes they expanded in all.
    """

    mesh: NavMesh
    dist: NDArray[np.float64]
    legs: dict[tuple[int, int], NDArray[np.float64]]
    build_seconds: float
    mesh_seconds: float
    n_queries: int
    expanded: int

    @property
    def max_edge(self) -> float:
        """No mesh-edge limit: the legs do not follow mesh edges."""
        return float("inf")

    @property
    def n_nodes(self) -> int:
        return int(len(self.mesh.vx))

    def leg(self, a: int, b: int, *, taut: bool = True) -> NDArray[np.float64]:
        """Points ``(p, 2)`` of the exact shortest path from stop ``a`` to stop ``b`` (``taut``
        is accepted for :class:`~weldplan.planar.tour_order.TourGraph`'s signature: the path
        is already taut)."""
        if a == b:
            raise ValueError("a leg joins two different stops")
        P = self.legs[(min(a, b), max(a, b))]
        return P if a < b else P[::-1]

    def polyline(
        self, order: ArrayLike, *, taut: bool = True
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """The closed tour ``0 -> order... -> 0`` as points ``(p, 2)`` and the index in it of
        each stop visited (``(t + 2,)``), as :meth:`TourGraph.polyline
        <weldplan.planar.tour_order.TourGraph.polyline>`."""
        seq = [0, *[int(v) for v in order], 0]
        pts = [self.leg(seq[0], seq[1])]
        at = [0, len(pts[0]) - 1]
        for a, b in zip(seq[1:-1], seq[2:], strict=True):
            leg = self.leg(a, b)
            pts.append(leg[1:])
            at.append(at[-1] + len(leg) - 1)
        return np.concatenate(pts), np.array(at, dtype=np.int64)


def tour_navmesh(task: Any) -> tuple[NavMesh, NDArray[np.float64], float]:
    """The navigation mesh of ``task``'s map and the affine map into it: returns
    ``(mesh, origin (2,), scale)`` with mesh coordinates ``(p - origin) / scale``."""
    from weldplan.planar.anyangle import scenario_navmesh
    from weldplan.planar.navmesh import grid_navmesh

    if task.scenario is None:
        sp = task.space
        return NavMesh(sp.vertices_xy, list(sp.polygon_vertices)), np.zeros(2), 1.0
    sc = task.scenario
    obs, grid, b = sc.obstacles, sc.grid, np.asarray(sc.bounds, dtype=np.float64)
    if grid is not None and not len(obs.circles) and not obs.polygons:
        o = np.asarray(grid.origin, dtype=np.float64)
        extent = np.concatenate([o, o + np.asarray(grid.occupied.shape) * grid.cell])
        if np.allclose(extent, b):  # the grid is the whole map: mesh its cells directly
            return grid_navmesh(~np.asarray(grid.occupied, dtype=bool)), o, float(grid.cell)
    return scenario_navmesh(obs, b), np.zeros(2), 1.0


def build_anyangle_graph(task: Any) -> AnyAngleTourGraph:
    """Polyanya between every pair of ``task``'s stops (module docstring).

    Raises
    ------
    PlanningError
        When a stop is off the mesh or two stops are not connected.
    """
    t0 = time.perf_counter()
    mesh, origin, scale = tour_navmesh(task)
    mesh_s = time.perf_counter() - t0
    S = (np.asarray(task.stops, dtype=np.float64) - origin) / scale
    k = len(S)
    planner = Polyanya(mesh)
    dist = np.zeros((k, k))
    legs: dict[tuple[int, int], NDArray[np.float64]] = {}
    expanded = 0
    for a in range(k):
        for b in range(a + 1, k):
            r = planner.query(S[a], S[b])
            if not r.found:
                raise PlanningError(
                    f"{task.name}: no path between stop {a} {task.stops[a].tolist()} and stop "
                    f"{b} {task.stops[b].tolist()} on the navigation mesh"
                )
            P = np.asarray(r.points, dtype=np.float64) * scale + origin
            P[0], P[-1] = task.stops[a], task.stops[b]  # exact ends, no round trip
            legs[(a, b)] = P
            dist[a, b] = dist[b, a] = r.length * scale
            expanded += r.expanded
    seconds = time.perf_counter() - t0
    log.info("%s: %d Polyanya legs in %.3f s (mesh %.3f s)", task.name, len(legs), seconds, mesh_s)
    return AnyAngleTourGraph(
        mesh=mesh,
        dist=dist,
        legs=legs,
        build_seconds=seconds,
        mesh_seconds=mesh_s,
        n_queries=len(legs),
        expanded=expanded,
    )
