"""Exact any-angle shortest paths by visibility graph, the independent cross-check of Polyanya.

The shortest path among polygonal obstacles runs through obstacle vertices where free space is
reflex, so Dijkstra over the visibility graph of those vertices (plus start and goal) is exact.
Circles are handled with a stated tolerance: their candidate turning points are the vertices of
a circumscribed regular ``circle_sides``-gon, while visibility is judged against the true
circles; the result is a feasible path at most about ``(pi / n)^2 / 3`` (relative, on the arcs)
longer than the true optimum (2e-4 for the default n = 128). A path may not squeeze through a
point where two obstacles touch (:meth:`Obstacles2D.pinch_points`). The space is an
:class:`~weldplan.geometry.obstacles2d.Obstacles2D` or a navigation mesh's
:class:`~weldplan.planar.meshspace.MeshFreeSpace`.
"""

from __future__ import annotations

import heapq
import logging
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from weldplan.errors import PlanningError
from weldplan.geometry.obstacles2d import GRAZE_TOL
from weldplan.geometry.pathmetrics import path_length
from weldplan.planar.exact_path import ExactPath
from weldplan.planar.meshspace import MeshFreeSpace

log = logging.getLogger(__name__)

#: sides of the polygon whose vertices stand in for a circle's turning points
CIRCLE_SIDES = 128
#: segments tested per vectorised chunk when building a visibility graph
CHUNK = 20_000


def candidate_vertices(obstacles: Any, circle_sides: int = CIRCLE_SIDES) -> NDArray[np.float64]:
    """Points where a shortest path may turn: obstacle vertices with one free fan of more
    than 180 degrees around them (sampled at 128 directions, so reflex angles within 3 degrees
    of straight are missed), and the vertices of circumscribed polygons of circles."""
    if isinstance(obstacles, MeshFreeSpace):
        return obstacles.corner_vertices()
    verts = obstacles.vertices()
    keep = np.zeros(0, dtype=bool)
    if len(verts):
        runs, frac = obstacles._free_fans(verts, n_dir=128)
        keep = (runs == 1) & (frac > 0.5) & (frac < 1.0)
    parts = [verts[keep]] if len(verts) else []
    if len(obstacles.circles):
        n = int(circle_sides)
        ang = (np.arange(n) + 0.5) * 2 * np.pi / n
        # 1e-7 beyond the circumscribed polygon, so that its edges clear the circle despite
        # rounding (a tangent's chord grows like the square root of the rounding error)
        unit = np.stack([np.cos(ang), np.sin(ang)], 1) * ((1 + 1e-7) / np.cos(np.pi / n))
        c = obstacles.circles
        ring = (c[:, None, :2] + c[:, None, 2:3] * unit).reshape(-1, 2)
        ring = ring[obstacles.clearance(ring) >= -GRAZE_TOL * obstacles.scale]
        parts.append(ring)
    if not parts:
        return np.zeros((0, 2))
    return np.concatenate(parts)


def _visible_pairs(space: Any, pts: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    n = len(pts)
    i, j = np.triu_indices(n, 1)
    ok = np.zeros(len(i), dtype=bool)
    for s in range(0, len(i), CHUNK):
        sl = slice(s, s + CHUNK)
        ok[sl] = space.segments_free(pts[i[sl]], pts[j[sl]])
    return i[ok], j[ok]


def visibility_shortest_path(
    obstacles: Any,
    start: ArrayLike,
    goal: ArrayLike,
    *,
    bounds: ArrayLike | None = None,
    circle_sides: int = CIRCLE_SIDES,
) -> ExactPath:
    """Any-angle shortest path from ``start`` to ``goal`` by the visibility graph.

    Parameters
    ----------
    obstacles
        :class:`Obstacles2D` (rectangles, polygons, circles) or :class:`MeshFreeSpace`.
    start, goal
        ``(2,)`` points in free space.
    bounds
        ``(xmin, ymin, xmax, ymax)``: turning points outside are dropped (the map is convex, so
        straight segments between points inside stay inside).
    circle_sides
        Circles' turning points are the vertices of circumscribed regular polygons with this
        many sides (see the module docstring for the tolerance).

    Raises
    ------
    PlanningError
        When the goal cannot be reached.
    """
    s = np.asarray(start, dtype=np.float64).reshape(2)
    g = np.asarray(goal, dtype=np.float64).reshape(2)
    cand = candidate_vertices(obstacles, circle_sides)
    if bounds is not None:
        b = np.asarray(bounds, dtype=np.float64)
        eps = 1e-9 * max(b[2] - b[0], b[3] - b[1])
        inside = (
            (cand[:, 0] >= b[0] - eps)
            & (cand[:, 0] <= b[2] + eps)
            & (cand[:, 1] >= b[1] - eps)
            & (cand[:, 1] <= b[3] + eps)
        )
        cand = cand[inside]
    if bool(space_free(obstacles, s, g)):
        return ExactPath(
            points=(tuple(s), tuple(g)),
            length=float(np.linalg.norm(g - s)),
            method="visibility-graph",
            expanded=2,
        )
    pts = np.concatenate([s[None], g[None], cand])
    i, j = _visible_pairs(obstacles, pts)
    return _graph_shortest_path(pts, i, j)


def _graph_shortest_path(
    pts: NDArray[np.float64], i: NDArray[np.int64], j: NDArray[np.int64]
) -> ExactPath:
    """Dijkstra from node 0 (start) to node 1 (goal) over the visible pairs ``(i, j)``."""
    n = len(pts)
    w = np.linalg.norm(pts[i] - pts[j], axis=1)
    graph = coo_matrix((w, (i, j)), shape=(n, n)).tocsr()
    dist, pred = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    return _traced_path(pts, dist, pred, expanded=n)


def _traced_path(
    pts: NDArray[np.float64], cost: NDArray[np.float64], parent: NDArray, *, expanded: int
) -> ExactPath:
    """The path from node 0 (start) to node 1 (goal) traced back through ``parent``.

    Raises
    ------
    PlanningError
        When the goal's ``cost`` is infinite (not reached).
    """
    if not np.isfinite(cost[1]):
        raise PlanningError("the goal cannot be reached from the start")
    order = [1]
    while order[-1] != 0:
        order.append(int(parent[order[-1]]))
    path = pts[order[::-1]]
    return ExactPath(
        points=tuple((float(x), float(y)) for x, y in path),
        length=float(path_length(path)),
        method="visibility-graph",
        expanded=expanded,
    )


def space_free(space: Any, a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
    """Whether the straight segment ``a -> b`` is free in ``space``."""
    return bool(space.segments_free(a[None], b[None])[0])


class VisibilityGraph:
    """A visibility graph built once and queried for many start/goal pairs.

    Turning points and their mutual visibility are computed at construction; each
    :meth:`shortest_path` adds the start and goal and runs Dijkstra.
    """

    def __init__(self, space: Any, *, circle_sides: int = CIRCLE_SIDES) -> None:
        self.space = space
        self.nodes = candidate_vertices(space, circle_sides)
        i, j = _visible_pairs(space, self.nodes)
        w = np.linalg.norm(self.nodes[i] - self.nodes[j], axis=1)
        self._i, self._j, self._w = i, j, w
        log.debug("visibility graph: %d nodes, %d edges", len(self.nodes), len(i))

    def shortest_path(self, start: ArrayLike, goal: ArrayLike) -> ExactPath:
        s = np.asarray(start, dtype=np.float64).reshape(2)
        g = np.asarray(goal, dtype=np.float64).reshape(2)
        if space_free(self.space, s, g):
            return ExactPath(
                points=(tuple(s), tuple(g)),
                length=float(np.linalg.norm(g - s)),
                method="visibility-graph",
                expanded=2,
            )
        m = len(self.nodes)
        ends = np.stack([s, g])
        A = np.repeat(ends, m, axis=0)
        B = np.tile(self.nodes, (2, 1))
        vis = self.space.segments_free(A, B).reshape(2, m)
        ii = [self._i + 2, self._j + 2]
        src = np.nonzero(vis[0])[0]
        dst = np.nonzero(vis[1])[0]
        i = np.concatenate([ii[0], np.zeros(len(src), int), np.ones(len(dst), int)])
        j = np.concatenate([ii[1], src + 2, dst + 2])
        pts = np.concatenate([ends, self.nodes])
        return _graph_shortest_path(pts, i, j)


def mesh_shortest_path_bounded(
    mesh: MeshFreeSpace, start: ArrayLike, goal: ArrayLike, bound: float
) -> ExactPath:
    """Any-angle shortest path on a large mesh when it is no longer than ``bound``.

    Every path of length ``<= bound`` lies in the ellipse ``|p - s| + |p - g| <= bound``, so
    the visibility graph is built on the crop of the mesh around that ellipse's bounding box
    (:meth:`MeshFreeSpace.crop`) with the corner vertices inside the ellipse as turning
    points. The result is the exact visibility-graph length whenever the true shortest path is
    at most ``bound``; otherwise :class:`PlanningError` (no path within the bound). The cost
    grows with the ellipse: short queries are cheap, long ones on big meshes are not.
    """
    s = np.asarray(start, dtype=np.float64).reshape(2)
    g = np.asarray(goal, dtype=np.float64).reshape(2)
    bound = float(bound)
    c = 0.5 * (s + g)
    # the ellipse's bounding box (foci s, g; major axis bound)
    a = 0.5 * bound
    f = 0.5 * float(np.linalg.norm(g - s))
    b = math.sqrt(max(a * a - f * f, 0.0))
    u = (g - s) / (2 * f) if f > 0 else np.array([1.0, 0.0])
    half = np.sqrt((a * u) ** 2 + (b * u[::-1]) ** 2) + 1e-9
    sub = mesh.crop(c - half, c + half)
    nodes = sub.corner_vertices()
    inside = np.linalg.norm(nodes - s, axis=1) + np.linalg.norm(nodes - g, axis=1) <= bound + 1e-9
    nodes = nodes[inside]
    if space_free(sub, s, g):
        return ExactPath(
            points=(tuple(s), tuple(g)),
            length=float(np.linalg.norm(g - s)),
            method="visibility-graph",
            expanded=2,
        )
    pts = np.concatenate([s[None], g[None], nodes])
    return _lazy_visibility_astar(sub, pts)


def _lazy_visibility_astar(space: Any, pts: NDArray[np.float64]) -> ExactPath:
    """A* from ``pts[0]`` to ``pts[1]`` over the visibility graph of ``pts``, with each node's
    visible neighbours computed only when it is expanded (one vectorised check of the
    segments to every node). The Euclidean heuristic is consistent, so the path is the
    visibility graph's shortest."""
    n = len(pts)
    goal = pts[1]
    gcost = np.full(n, np.inf)
    parent = np.full(n, -1, dtype=np.int64)
    closed = np.zeros(n, dtype=bool)
    gcost[0] = 0.0
    heap = [(float(np.linalg.norm(goal - pts[0])), 0)]
    expanded = 0
    while heap:
        _, v = heapq.heappop(heap)
        if closed[v]:
            continue
        if v == 1:
            break
        closed[v] = True
        expanded += 1
        cand = np.nonzero(~closed)[0]
        vis = space.segments_free(np.broadcast_to(pts[v], (len(cand), 2)), pts[cand])
        cand = cand[vis]
        nd = gcost[v] + np.linalg.norm(pts[cand] - pts[v], axis=1)
        better = nd < gcost[cand]
        cand, nd = cand[better], nd[better]
        gcost[cand] = nd
        parent[cand] = v
        f = nd + np.linalg.norm(pts[cand] - goal, axis=1)
        for fu, u in zip(f.tolist(), cand.tolist(), strict=True):
            heapq.heappush(heap, (fu, u))
    return _traced_path(pts, gcost, parent, expanded=expanded)
