"""Any-angle optima of planar maps by Polyanya: the map made a navigation mesh, then queried.

The free-space model is the visibility graph's (:func:`weldplan.planar.exact.candidate_vertices`):
rectangles and polygons as they are, each circle as the circumscribed regular polygon with
``circle_sides`` sides (default :data:`~weldplan.planar.exact.CIRCLE_SIDES`) that the visibility
graph takes its turning points from, so the optimum is a feasible path for the true circles and
at most about ``(pi / n)^2 / 3`` longer on the arcs, and the gaps reported against it stay
comparable with the visibility-graph baseline they replace. Obstacles that touch pinch free
space to a point that no path crosses (the mesh has no edge there), as in the visibility graph.

The mesh: the obstacle outlines and the map frame triangulated by Triangle (constrained
Delaunay, no quality refinement: Polyanya needs no small triangles), the triangles whose
centroid lies in an obstacle dropped (:func:`scenario_navmesh`).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import PlanningError
from weldplan.planar.exact import CIRCLE_SIDES, ExactPath
from weldplan.planar.navmesh import NavMesh
from weldplan.planar.polyanya import Polyanya

log = logging.getLogger(__name__)


def circle_polygons(circles: ArrayLike, circle_sides: int = CIRCLE_SIDES) -> list[NDArray]:
    """Each circle ``(cx, cy, r)`` as the circumscribed ``n``-gon whose vertices are the
    visibility graph's turning points (vertex ``k`` at angle ``(k + 1/2) 2 pi / n``, radius
    ``r (1 + 1e-7) / cos(pi / n)``; see :func:`weldplan.planar.exact.candidate_vertices`)."""
    n = int(circle_sides)
    ang = (np.arange(n) + 0.5) * 2 * np.pi / n
    unit = np.stack([np.cos(ang), np.sin(ang)], 1) * ((1 + 1e-7) / np.cos(np.pi / n))
    return [c[:2] + c[2] * unit for c in np.asarray(circles, dtype=np.float64).reshape(-1, 3)]


def obstacle_rings(obstacles: Any, circle_sides: int = CIRCLE_SIDES) -> list[NDArray]:
    """Every obstacle's outline ``(v, 2)``: polygons, rectangles, circles as polygons."""
    rings = [np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in obstacles.polygons]
    for x0, y0, x1, y1 in np.asarray(obstacles.rectangles, dtype=np.float64).reshape(-1, 4):
        rings.append(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
    rings += circle_polygons(obstacles.circles, circle_sides)
    return rings


def scenario_navmesh(
    obstacles: Any, bounds: ArrayLike, *, circle_sides: int = CIRCLE_SIDES
) -> NavMesh:
    """The navigation mesh of the free space of ``obstacles``
    (:class:`~weldplan.geometry.obstacles2d.Obstacles2D`) inside ``bounds``
    ``(xmin, ymin, xmax, ymax)``, circles as polygons (module docstring)."""
    from weldplan.geometry.obstacles2d import Obstacles2D
    from weldplan.planar.meshmap import triangulate_segments

    x0, y0, x1, y1 = (float(v) for v in np.asarray(bounds, dtype=np.float64).reshape(4))
    rings = [np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])]
    rings += obstacle_rings(obstacles, circle_sides)
    A, B = split_overlaps(np.concatenate(rings), np.concatenate([np.roll(r, -1, 0) for r in rings]))
    solid = Obstacles2D(polygons=tuple(rings[1:]))
    eps = 1e-9 * max(x1 - x0, y1 - y0)

    def keep(c: NDArray[np.float64]) -> NDArray[np.bool_]:
        inside = (c[:, 0] > x0 + eps) & (c[:, 0] < x1 - eps)
        inside &= (c[:, 1] > y0 + eps) & (c[:, 1] < y1 - eps)
        if len(rings) > 1:
            inside[inside] = ~solid.contains(c[inside])
        return inside

    tmap = triangulate_segments(A, B, keep, max_edge=math.inf, min_angle=0.0)
    return NavMesh.from_triangles(tmap.nodes, tmap.cells)


def split_overlaps(
    A: NDArray[np.float64], B: NDArray[np.float64], *, chunk: int = 2_000_000
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Segments ``A -> B (s, 2)`` cut at every segment end lying inside another segment, with
    duplicates (either direction) removed: touching or overlapping obstacle outlines give
    collinear overlapping segments, which Triangle rejects; after the cut they are identical
    pieces, kept once. Ends closer than ``1e-9`` of the map's size are merged first."""
    P = np.concatenate([A, B])
    scale = float(np.ptp(P, axis=0).max()) or 1.0
    tol = 1e-9 * scale
    key = np.round(P / tol).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    U = P[first]
    ia, ib = inv.reshape(-1)[: len(A)], inv.reshape(-1)[len(A) :]
    keep = ia != ib
    ia, ib = ia[keep], ib[keep]
    pieces_a, pieces_b = [], []
    step = max(1, chunk // max(1, len(U)))
    for s0 in range(0, len(ia), step):
        a, b = U[ia[s0 : s0 + step]], U[ib[s0 : s0 + step]]
        d = b - a
        L2 = np.sum(d * d, axis=1)
        w = U[None, :, :] - a[:, None, :]
        t = np.sum(w * d[:, None, :], axis=2) / L2[:, None]
        perp = np.abs(w[..., 0] * d[:, None, 1] - w[..., 1] * d[:, None, 0]) / np.sqrt(L2)[:, None]
        inner = (perp <= tol) & (t > 0) & (t < 1)
        for k in range(len(a)):
            cut = np.nonzero(inner[k])[0]
            ids = np.concatenate([[ia[s0 + k]], cut[np.argsort(t[k, cut])], [ib[s0 + k]]])
            pieces_a.append(ids[:-1])
            pieces_b.append(ids[1:])
    pa, pb = np.concatenate(pieces_a), np.concatenate(pieces_b)
    pairs = np.unique(np.sort(np.stack([pa, pb], axis=1), axis=1), axis=0)
    return U[pairs[:, 0]], U[pairs[:, 1]]


def polyanya_shortest_path(
    mesh: NavMesh | Polyanya, start: ArrayLike, goal: ArrayLike
) -> ExactPath:
    """The any-angle shortest path on a mesh as an :class:`ExactPath` (``method`` =
    ``"polyanya"``, ``expanded`` = search nodes expanded).

    Raises
    ------
    PlanningError
        When the goal cannot be reached (or a point is off the mesh).
    """
    planner = mesh if isinstance(mesh, Polyanya) else Polyanya(mesh)
    r = planner.query(start, goal)
    if not r.found:
        raise PlanningError("the goal cannot be reached from the start")
    return ExactPath(
        points=tuple((float(x), float(y)) for x, y in r.points),
        length=float(r.length),
        method="polyanya",
        expanded=r.expanded,
    )
