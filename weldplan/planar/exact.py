"""Exact baselines for the planar tables: any-angle shortest paths and 8-connected grid A*.

The production any-angle planner is Polyanya (:mod:`weldplan.planar.polyanya`, used by
``exact_optimum`` and ``weldplan bench queries``); the visibility graph here is the
independent cross-check its tests compare against.

* :func:`visibility_shortest_path`: the shortest path among polygonal obstacles runs through
  obstacle vertices where free space is reflex, so Dijkstra over the visibility graph of those
  vertices (plus start and goal) is exact. Circles are handled with a stated tolerance: their
  candidate turning points are the vertices of a circumscribed regular ``circle_sides``-gon,
  while visibility is judged against the true circles; the result is a feasible path at most
  about ``(pi / n)^2 / 3`` (relative, on the arcs) longer than the true optimum
  (2e-4 for the default n = 128). A path may not squeeze through a point where two obstacles
  touch (:meth:`Obstacles2D.pinch_points`).
* :func:`astar_grid`: A* on an occupancy grid, 8-connected, octile costs (1 and sqrt 2), no
  corner cutting (a diagonal move needs both orthogonal neighbours free), the rules of the
  Moving AI benchmarks.
* Readers for Moving AI ``.map``/``.scen`` files and Polyanya ``.mesh`` (v2) navigation meshes,
  and :class:`MeshFreeSpace`, the free space of a mesh with the same segment queries as
  :class:`Obstacles2D`, so the visibility graph runs on either.
"""

from __future__ import annotations

import heapq
import json
import logging
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from weldplan.errors import InputError, PlanningError
from weldplan.geometry.obstacles2d import GRAZE_TOL, point_segment_distance
from weldplan.geometry.pathmetrics import path_length

log = logging.getLogger(__name__)

SQRT2 = math.sqrt(2.0)
#: sides of the polygon whose vertices stand in for a circle's turning points
CIRCLE_SIDES = 128
#: segments tested per vectorised chunk when building a visibility graph
CHUNK = 20_000


@dataclass(frozen=True)
class ExactPath:
    """A shortest path found by an exact planner.

    Attributes
    ----------
    points
        ``((n, 2))`` waypoints from start to goal (map units; cell centres for grids).
    length
        Its length.
    method
        ``"visibility-graph"`` or ``"astar-8"``.
    expanded
        Nodes of the graph (visibility graph) or cells expanded (A*).
    """

    points: tuple[tuple[float, float], ...]
    length: float
    method: str
    expanded: int = 0

    @property
    def points_array(self) -> NDArray[np.float64]:
        return np.asarray(self.points, dtype=np.float64).reshape(-1, 2)

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_json(cls, text: str) -> ExactPath:
        d = json.loads(text)
        d["points"] = tuple(tuple(p) for p in d["points"])
        return cls(**d)


# ---------------------------------------------------------------------------- visibility graph
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
    if not np.isfinite(dist[1]):
        raise PlanningError("the goal cannot be reached from the start")
    order = [1]
    while order[-1] != 0:
        order.append(int(pred[order[-1]]))
    path = pts[order[::-1]]
    return ExactPath(
        points=tuple((float(x), float(y)) for x, y in path),
        length=float(path_length(path)),
        method="visibility-graph",
        expanded=n,
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
    if not np.isfinite(gcost[1]):
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


# ---------------------------------------------------------------------------------------- A*
def astar_grid(free: ArrayLike, start: tuple[int, int], goal: tuple[int, int]) -> ExactPath:
    """Shortest 8-connected path on a grid without corner cutting (octile costs).

    Parameters
    ----------
    free
        ``(nx, ny) bool``: traversable cells, indexed ``[i, j]``.
    start, goal
        Cell indices ``(i, j)``.

    Returns
    -------
    :class:`ExactPath` whose points are the cells ``(i, j)`` of the path (as floats) and whose
    length is in cells. A heap-based A* with the octile heuristic (consistent, so the first
    time the goal is popped its cost is optimal).

    Raises
    ------
    PlanningError
        When start or goal is blocked or the goal is unreachable.
    """
    F = np.asarray(free, dtype=bool)
    nx, ny = F.shape
    si, sj = int(start[0]), int(start[1])
    gi, gj = int(goal[0]), int(goal[1])
    for name, (a, b) in (("start", (si, sj)), ("goal", (gi, gj))):
        if not (0 <= a < nx and 0 <= b < ny) or not F[a, b]:
            raise PlanningError(f"{name} cell {(a, b)} is blocked or outside the grid")
    # flat indices over a padded grid so that neighbours never wrap
    W = ny + 2
    pad = np.zeros((nx + 2, ny + 2), dtype=bool)
    pad[1:-1, 1:-1] = F
    ok = pad.ravel().tolist()
    s = (si + 1) * W + sj + 1
    t = (gi + 1) * W + gj + 1
    n_all = len(ok)
    g_cost = [math.inf] * n_all
    parent = [-1] * n_all
    closed = bytearray(n_all)
    g_cost[s] = 0.0
    gx, gy = gi + 1, gj + 1
    sq2 = SQRT2
    k2 = SQRT2 - 2.0
    # (offset, cost, orthogonal neighbours a diagonal move needs free)
    moves = (
        (W, 1.0, 0, 0),
        (-W, 1.0, 0, 0),
        (1, 1.0, 0, 0),
        (-1, 1.0, 0, 0),
        (W + 1, sq2, W, 1),
        (W - 1, sq2, W, -1),
        (-W + 1, sq2, -W, 1),
        (-W - 1, sq2, -W, -1),
    )

    def h(v: int) -> float:
        dx = abs(v // W - gx)
        dy = abs(v % W - gy)
        return dx + dy + k2 * (dx if dx < dy else dy)

    heap = [(h(s), 0.0, s)]
    push, pop = heapq.heappush, heapq.heappop
    expanded = 0
    while heap:
        _, gc, v = pop(heap)
        if closed[v]:
            continue
        if v == t:
            break
        closed[v] = 1
        expanded += 1
        for d, c, a, b in moves:
            u = v + d
            if not ok[u] or closed[u] or (a and not (ok[v + a] and ok[v + b])):
                continue
            nc = gc + c
            if nc < g_cost[u]:
                g_cost[u] = nc
                parent[u] = v
                push(heap, (nc + h(u), nc, u))
    else:
        raise PlanningError(f"goal cell {(gi, gj)} cannot be reached from {(si, sj)}")
    cells = []
    v = t
    while v != -1:
        cells.append((float(v // W - 1), float(v % W - 1)))
        v = parent[v]
    cells.reverse()
    return ExactPath(
        points=tuple(cells), length=float(g_cost[t]), method="astar-8", expanded=expanded
    )


#: the eight moves of the Moving AI grids: (di, dj)
_MOVES8 = ((1, 0), (0, 1), (1, 1), (1, -1))


def grid_graph(free: ArrayLike) -> Any:
    """The 8-connected grid of :func:`astar_grid` as a sparse graph (scipy CSR, undirected).

    Node ``i * ny + j`` is cell ``(i, j)``; straight moves cost 1, diagonal ones sqrt(2) and
    need both orthogonal neighbours free (no corner cutting), exactly the moves of
    :func:`astar_grid`. Built with numpy in one pass per direction (a 512 x 512 map: 0.2 s).
    """
    from scipy.sparse import csr_matrix

    F = np.asarray(free, dtype=bool)
    nx, ny = F.shape
    I, J = np.nonzero(F)
    rows, cols, cost = [], [], []
    for di, dj in _MOVES8:
        I2, J2 = I + di, J + dj
        ok = (I2 >= 0) & (I2 < nx) & (J2 >= 0) & (J2 < ny)
        a, b, a2, b2 = I[ok], J[ok], I2[ok], J2[ok]
        ok = F[a2, b2]
        if di and dj:
            ok &= F[a + di, b] & F[a, b + dj]
        rows.append(a[ok] * ny + b[ok])
        cols.append(a2[ok] * ny + b2[ok])
        cost.append(np.full(int(ok.sum()), SQRT2 if di and dj else 1.0))
    r, c, w = np.concatenate(rows), np.concatenate(cols), np.concatenate(cost)
    return csr_matrix((w, (r, c)), shape=(nx * ny, nx * ny))


def grid_lengths(
    free: ArrayLike,
    starts: ArrayLike,
    goals: ArrayLike,
    *,
    graph: Any = None,
    limits: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Shortest 8-connected lengths (cells) for many queries, by scipy's compiled Dijkstra.

    The same graph as :func:`astar_grid` (see :func:`grid_graph`), one single-source search
    per query in C: about 0.05 s a query on a 512 x 512 map where the Python A* takes up to
    0.8 s (it floods mazes whatever the heuristic). ``limits (n,)``, when given, stop each
    search beyond that length (``inf`` is returned past it): a bound on the work, never a
    change to a length found within it.

    Parameters
    ----------
    free
        ``(nx, ny) bool`` traversable cells.
    starts, goals
        ``(n, 2)`` cell indices.
    graph
        A prebuilt :func:`grid_graph` of ``free`` (built here when None).
    limits
        Optional ``(n,)`` search bounds.

    Returns
    -------
    ``(n,)`` lengths in cells; ``inf`` where the goal is unreachable (or beyond its limit).
    """
    from scipy.sparse.csgraph import dijkstra as sp_dijkstra

    F = np.asarray(free, dtype=bool)
    ny = F.shape[1]
    G = grid_graph(F) if graph is None else graph
    S = np.asarray(starts, dtype=np.int64).reshape(-1, 2)
    T = np.asarray(goals, dtype=np.int64).reshape(-1, 2)
    out = np.full(len(S), np.inf)
    for k in range(len(S)):
        s = int(S[k, 0] * ny + S[k, 1])
        t = int(T[k, 0] * ny + T[k, 1])
        lim = np.inf if limits is None else float(np.asarray(limits)[k])
        d = sp_dijkstra(G, directed=False, indices=s, limit=lim)
        out[k] = d[t]
    return out


def octile(di: ArrayLike, dj: ArrayLike) -> NDArray[np.float64]:
    """Octile distance for cell offsets (the A* heuristic, exact on an empty grid)."""
    a = np.abs(np.asarray(di, dtype=np.float64))
    b = np.abs(np.asarray(dj, dtype=np.float64))
    return a + b + (SQRT2 - 2.0) * np.minimum(a, b)


# ------------------------------------------------------------------------- Moving AI / Polyanya
MOVINGAI_PASSABLE = frozenset(".GS")


def read_movingai_map(path: str | Path) -> NDArray[np.bool_]:
    """Traversable cells of a Moving AI ``.map`` file: ``(width, height) bool`` indexed
    ``[x, y]`` with y the row as written (``.``, ``G`` and ``S`` are traversable)."""
    path = Path(path)
    lines = path.read_text().splitlines()
    try:
        h = int(lines[1].split()[1])
        w = int(lines[2].split()[1])
    except (IndexError, ValueError):
        raise InputError(
            "expected 'height H' and 'width W' header lines", path=path, line=2
        ) from None
    rows = lines[4 : 4 + h]
    if len(rows) != h or any(len(r) < w for r in rows):
        raise InputError(f"expected {h} rows of {w} cells", path=path, line=5)
    grid = np.array([[c in MOVINGAI_PASSABLE for c in r[:w]] for r in rows], dtype=bool)
    return grid.T


@dataclass(frozen=True)
class ScenarioSet:
    """Queries of a Moving AI ``.scen`` file: ``start, goal (n, 2) int`` as ``(x, y)``,
    ``length (n,)`` optimal octile lengths, ``bucket (n,)``."""

    start: NDArray[np.int64]
    goal: NDArray[np.int64]
    length: NDArray[np.float64]
    bucket: NDArray[np.int64]


def read_scen(path: str | Path) -> ScenarioSet:
    """Read a Moving AI ``.scen`` file (version 1)."""
    path = Path(path)
    rows = []
    for k, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip() or line.startswith("version"):
            continue
        f = line.split("\t") if "\t" in line else line.split()
        if len(f) < 9:
            raise InputError("expected 9 fields", path=path, line=k)
        try:
            rows.append((int(f[0]), int(f[4]), int(f[5]), int(f[6]), int(f[7]), float(f[8])))
        except ValueError:
            raise InputError("bad number", path=path, line=k) from None
    a = np.array(rows, dtype=np.float64).reshape(-1, 6)
    return ScenarioSet(
        start=a[:, 1:3].astype(np.int64),
        goal=a[:, 3:5].astype(np.int64),
        length=a[:, 5],
        bucket=a[:, 0].astype(np.int64),
    )


class MeshFreeSpace:
    """The free space of a Polyanya navigation mesh (``.mesh`` version 2).

    The mesh polygons tile free space; its boundary edges (a polygon on one side, ``-1`` on
    the other) form closed loops, so a point is free when a ray from it crosses the boundary
    an odd number of times. A segment is free when it crosses no boundary edge, the pieces
    between the boundary points it touches are free (or lie on the boundary: grazing), and it
    passes through no ambiguous vertex (one with two or more obstacle wedges, where obstacles
    touch). ``vertex_polys`` lists each vertex's neighbouring polygons in order, ``-1`` for
    obstacle.

    Vectorised over segments. Queries go through a uniform grid of the boundary edges
    (:class:`_EdgeIndex`, about one cell per edge): a point is tested against the edges of its
    horizontal band and its cell, a segment against the edges of the cells around samples along
    it, so the cost grows with the edges near the query instead of all of them (the Moving AI
    aurora navmesh has 35k boundary edges; the all-pairs arrays of a single segment's pieces
    against them took tens of GB).
    """

    def __init__(
        self,
        vertices: NDArray[np.float64],
        polygons: list[NDArray[np.int64]],
        poly_neighbours: list[NDArray[np.int64]],
        vertex_polys: list[list[int]],
    ) -> None:
        self.vertices_xy = vertices
        self.polygon_vertices = polygons
        self.polygon_neighbours = poly_neighbours
        self.vertex_polys = vertex_polys
        ea, eb = [], []
        for vs, nb in zip(polygons, poly_neighbours, strict=True):
            # Polyanya: neighbour k lies across the edge from vertex k-1 to vertex k
            for k in range(len(vs)):
                if nb[k] == -1:
                    ea.append(vertices[vs[k - 1]])
                    eb.append(vertices[vs[k]])
        self.edge_a = np.array(ea).reshape(-1, 2)
        self.edge_b = np.array(eb).reshape(-1, 2)
        lo = vertices.min(axis=0)
        hi = vertices.max(axis=0)
        self.scale = float(np.hypot(*(hi - lo)))
        runs = np.array([_obstacle_runs(vp) for vp in vertex_polys])
        self.ambiguous = vertices[runs >= 2]
        self._index = _EdgeIndex(self.edge_a, self.edge_b, 1e-9 * self.scale)

    @classmethod
    def read(cls, path: str | Path) -> MeshFreeSpace:
        path = Path(path)
        tok = path.read_text().split()
        if len(tok) < 4 or tok[0] != "mesh" or tok[1] != "2":
            raise InputError("not a Polyanya mesh version 2", path=path, line=1)
        nv, npoly = int(tok[2]), int(tok[3])
        k = 4
        verts = np.empty((nv, 2))
        vpolys: list[list[int]] = []
        for v in range(nv):
            verts[v] = float(tok[k]), float(tok[k + 1])
            n = int(tok[k + 2])
            vpolys.append([int(x) for x in tok[k + 3 : k + 3 + n]])
            k += 3 + n
        polys, neigh = [], []
        for _ in range(npoly):
            n = int(tok[k])
            polys.append(np.array([int(x) for x in tok[k + 1 : k + 1 + n]], dtype=np.int64))
            neigh.append(np.array([int(x) for x in tok[k + 1 + n : k + 1 + 2 * n]]))
            k += 1 + 2 * n
        return cls(verts, polys, neigh, vpolys)

    def _on_boundary(self, P: NDArray[np.float64], tol: float) -> NDArray[np.bool_]:
        """Whether points ``(n, 2)`` are within ``tol`` (at most the index's padding) of a
        boundary edge."""
        ix = self._index
        out = np.zeros(len(P), dtype=bool)
        for s in range(0, len(P), ix.chunk_points):
            Q = P[s : s + ix.chunk_points]
            pi, ei = ix.pairs(np.arange(len(Q)), ix.cell_of(Q), ix.cell_ptr, ix.cell_idx)
            d = point_segment_distance(Q[pi], ix.a[ei], ix.b[ei])
            out[s : s + len(Q)] = np.bincount(pi[d <= tol], minlength=len(Q)) > 0
        return out

    def contains_free(self, P: ArrayLike) -> NDArray[np.bool_]:
        """Whether points ``(..., 2)`` lie in the mesh (interior or boundary)."""
        P = np.asarray(P, dtype=np.float64)
        lead = P.shape[:-1]
        Q = P.reshape(-1, 2)
        ix = self._index
        inside = np.zeros(len(Q), dtype=bool)
        for s in range(0, len(Q), ix.chunk_points):
            R = Q[s : s + ix.chunk_points]
            # crossings of the ray to +x with the edges of the point's horizontal band
            pi, ei = ix.pairs(np.arange(len(R)), ix.band_of(R), ix.band_ptr, ix.band_idx)
            a, b = ix.a[ei], ix.b[ei]
            py, px = R[pi, 1], R[pi, 0]
            cond = (a[:, 1] > py) != (b[:, 1] > py)
            dy = b[:, 1] - a[:, 1]
            xint = a[:, 0] + (py - a[:, 1]) * (b[:, 0] - a[:, 0]) / np.where(dy == 0, 1.0, dy)
            hits = np.bincount(pi[cond & (px < xint)], minlength=len(R))
            inside[s : s + len(R)] = hits % 2 == 1
        rest = ~inside
        if np.any(rest):  # points on the boundary count as free (grazing)
            inside[rest] = self._on_boundary(Q[rest], 1e-9 * self.scale)
        return inside.reshape(lead)

    def segments_free(self, A: ArrayLike, B: ArrayLike) -> NDArray[np.bool_]:
        A = np.asarray(A, dtype=np.float64)
        B = np.asarray(B, dtype=np.float64)
        A, B = np.broadcast_arrays(A, B)
        lead = A.shape[:-1]
        A2, B2 = A.reshape(-1, 2), B.reshape(-1, 2)
        out = np.empty(len(A2), dtype=bool)
        ix = self._index
        # chunks of at most chunk_points segments and chunk_samples samples (long segments
        # are sampled at steps of half a grid cell to find their candidate edges)
        samples = np.ceil(np.linalg.norm(B2 - A2, axis=1) / (0.5 * ix.h)) + 1
        s = 0
        while s < len(A2):
            e = min(s + ix.chunk_points, len(A2))
            cut = int(np.searchsorted(np.cumsum(samples[s:e]), ix.chunk_samples, side="right"))
            e = s + max(1, min(cut, e - s))
            out[s:e] = self._free_chunk(A2[s:e], B2[s:e])
            s = e
        return out.reshape(lead)

    def _free_chunk(self, A: NDArray[np.float64], B: NDArray[np.float64]) -> NDArray[np.bool_]:
        tol = 1e-9 * self.scale
        n = len(A)
        si, ei = self._index.segment_pairs(A, B)
        a, b = self._index.a[ei], self._index.b[ei]
        d = B[si] - A[si]
        e = b - a
        den = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
        w = a - A[si]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / den
            u = (w[:, 0] * d[:, 1] - w[:, 1] * d[:, 0]) / den
        Ls = np.linalg.norm(B - A, axis=1)
        L = Ls[si]
        le = np.linalg.norm(e, axis=1)
        et, eu = tol / np.maximum(L, tol), tol / le
        ok = den != 0
        proper = ok & (t > et) & (t < 1 - et) & (u > eu) & (u < 1 - eu)
        free = np.bincount(si[proper], minlength=n) == 0
        # split at every touch (and at the projections of boundary vertices), test the pieces
        touch = ok & (t >= -et) & (t <= 1 + et) & (u >= -eu) & (u <= 1 + eu)
        seg = np.concatenate([np.arange(n), np.arange(n), si[touch]])
        ts = np.concatenate([np.zeros(n), np.ones(n), np.clip(t[touch], 0.0, 1.0)])
        o = np.lexsort((ts, seg))
        seg, ts = seg[o], ts[o]
        same = seg[1:] == seg[:-1]
        s0, t0, t1 = seg[1:][same], ts[:-1][same], ts[1:][same]
        long = (t1 - t0) * Ls[s0] > tol
        s0, mid = s0[long], 0.5 * (t0 + t1)[long]
        if len(s0):
            M = A[s0] + mid[:, None] * (B[s0] - A[s0])
            bad = s0[~self.contains_free(M)]
            free[bad] = False
        if len(self.ambiguous):
            amb = self.ambiguous
            step = max(1, 4_000_000 // len(amb))
            for c in range(0, n, step):
                Ac, Bc = A[c : c + step, None], B[c : c + step, None]
                dd = point_segment_distance(amb, Ac, Bc)
                end = (np.linalg.norm(amb - Ac, axis=-1) <= tol) | (
                    np.linalg.norm(amb - Bc, axis=-1) <= tol
                )
                free[c : c + step] &= ~np.any((dd <= tol) & ~end, axis=-1)
        return free

    def crop(self, lo: ArrayLike, hi: ArrayLike) -> MeshFreeSpace:
        """The sub-mesh of the polygons whose bounding boxes meet the box ``[lo, hi]``.

        Polygons left out become obstacle (``-1``) for their neighbours, so the crop adds
        walls, all outside the box: a path that stays in the box is free in the crop exactly
        when it is free in the whole mesh. Used to make queries on large meshes local
        (:func:`mesh_shortest_path_bounded`).
        """
        lo = np.asarray(lo, dtype=np.float64)
        hi = np.asarray(hi, dtype=np.float64)
        if "_poly_lo" not in self.__dict__:
            self._poly_lo = np.array(
                [self.vertices_xy[p].min(axis=0) for p in self.polygon_vertices]
            )
            self._poly_hi = np.array(
                [self.vertices_xy[p].max(axis=0) for p in self.polygon_vertices]
            )
        keep = np.nonzero(
            np.all(self._poly_hi >= lo, axis=1) & np.all(self._poly_lo <= hi, axis=1)
        )[0]
        new_id = np.full(len(self.polygon_vertices), -1, dtype=np.int64)
        new_id[keep] = np.arange(len(keep))
        used = (
            np.unique(np.concatenate([self.polygon_vertices[k] for k in keep]))
            if len(keep)
            else np.zeros(0, dtype=np.int64)
        )
        vmap = np.full(len(self.vertices_xy), -1, dtype=np.int64)
        vmap[used] = np.arange(len(used))
        polys = [vmap[self.polygon_vertices[k]] for k in keep]
        neigh = [
            np.where(
                self.polygon_neighbours[k] >= 0,
                new_id[np.maximum(self.polygon_neighbours[k], 0)],
                -1,
            )
            for k in keep
        ]
        vpolys = [[int(new_id[p]) if p >= 0 else -1 for p in self.vertex_polys[v]] for v in used]
        return MeshFreeSpace(self.vertices_xy[used], polys, neigh, vpolys)

    def corner_vertices(self) -> NDArray[np.float64]:
        """Vertices where free space is reflex (one obstacle wedge, free angle >= 180 deg)."""
        angle = np.zeros(len(self.vertices_xy))
        V = self.vertices_xy
        for poly in self.polygon_vertices:
            p = V[poly]
            prev = np.roll(p, 1, axis=0) - p
            nxt = np.roll(p, -1, axis=0) - p
            cosang = np.sum(prev * nxt, 1) / (
                np.linalg.norm(prev, axis=1) * np.linalg.norm(nxt, axis=1)
            )
            np.add.at(angle, poly, np.arccos(np.clip(cosang, -1, 1)))
        runs = np.array([_obstacle_runs(vp) for vp in self.vertex_polys])
        return V[(runs == 1) & (angle >= np.pi - 1e-9)]


class _EdgeIndex:
    """A uniform grid over line segments (the boundary edges of a navigation mesh).

    The cell size ``h`` gives about one cell per edge. Each edge is registered in every cell
    its bounding box (padded by ``pad``) overlaps, and in every horizontal band (a row of
    cells) its ``y`` range overlaps; both as CSR arrays (``*_ptr``, ``*_idx``).

    * A point within ``pad`` of an edge lies in a cell holding that edge.
    * Every edge crossing the horizontal line through a point is in the point's band.
    * Every edge touching a segment holds a cell within one cell of a sample of the segment
      taken at steps of ``h / 2`` (the touch point is within ``h / 4`` of a sample).
    """

    #: points (or segments) per chunk of a query
    chunk_points = 4096
    #: segment samples per chunk of a segment query (9 candidate cells each)
    chunk_samples = 200_000

    def __init__(self, a: NDArray[np.float64], b: NDArray[np.float64], pad: float) -> None:
        self.a, self.b = a, b
        n = max(len(a), 1)
        lo = np.minimum(a, b).min(axis=0) - pad if len(a) else np.zeros(2)
        hi = np.maximum(a, b).max(axis=0) + pad if len(a) else np.ones(2)
        span = float(max((hi - lo).max(), 1e-300))
        self.h = span / max(1.0, math.sqrt(n))
        self.lo = lo
        self.shape = np.maximum(1, np.ceil((hi - lo) / self.h).astype(np.int64) + 1)
        nx, ny = (int(v) for v in self.shape)
        emin = self._ij(np.minimum(a, b) - pad)
        emax = self._ij(np.maximum(a, b) + pad)
        # cells: each edge over its bounding-box cells
        cx = emax[:, 0] - emin[:, 0] + 1
        cy = emax[:, 1] - emin[:, 1] + 1
        cnt = cx * cy
        edge = np.repeat(np.arange(len(a)), cnt)
        k = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        i = emin[edge, 0] + k // cy[edge]
        j = emin[edge, 1] + k % cy[edge]
        self.cell_ptr, self.cell_idx = _csr(i * ny + j, edge, nx * ny)
        # bands: each edge over its rows
        edge = np.repeat(np.arange(len(a)), cy)
        k = np.arange(int(cy.sum())) - np.repeat(np.cumsum(cy) - cy, cy)
        self.band_ptr, self.band_idx = _csr(emin[edge, 1] + k, edge, ny)

    def _ij(self, P: NDArray[np.float64]) -> NDArray[np.int64]:
        ij = np.floor((P - self.lo) / self.h).astype(np.int64)
        return np.clip(ij, 0, self.shape - 1)

    def cell_of(self, P: NDArray[np.float64]) -> NDArray[np.int64]:
        ij = self._ij(P)
        return ij[:, 0] * int(self.shape[1]) + ij[:, 1]

    def band_of(self, P: NDArray[np.float64]) -> NDArray[np.int64]:
        return self._ij(P)[:, 1]

    @staticmethod
    def pairs(
        q: NDArray[np.int64], key: NDArray[np.int64], ptr: NDArray[np.int64], idx: NDArray[np.int64]
    ) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """``(query, edge)`` pairs: every edge stored under ``key[k]`` for query ``q[k]``."""
        start = ptr[key]
        cnt = ptr[key + 1] - start
        rep = np.repeat(np.arange(len(key)), cnt)
        off = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        return q[rep], idx[start[rep] + off]

    def segment_pairs(
        self, A: NDArray[np.float64], B: NDArray[np.float64]
    ) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Unique ``(segment, edge)`` pairs that may touch (see the class docstring)."""
        L = np.linalg.norm(B - A, axis=1)
        m = np.ceil(L / (0.5 * self.h)).astype(np.int64) + 1
        seg = np.repeat(np.arange(len(A)), m)
        k = np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m)
        t = k / np.maximum(m[seg] - 1, 1)
        S = A[seg] + t[:, None] * (B[seg] - A[seg])
        ij = np.floor((S - self.lo) / self.h).astype(np.int64)
        nx, ny = (int(v) for v in self.shape)
        off = np.array([(dx, dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1)])
        IJ = ij[:, None, :] + off[None]
        valid = (IJ[..., 0] >= 0) & (IJ[..., 0] < nx) & (IJ[..., 1] >= 0) & (IJ[..., 1] < ny)
        cell = (IJ[..., 0] * ny + IJ[..., 1])[valid]
        sc = np.unique(np.repeat(seg, 9)[valid.reshape(-1)] * (nx * ny) + cell)
        si, ei = self.pairs(sc // (nx * ny), sc % (nx * ny), self.cell_ptr, self.cell_idx)
        key = np.unique(si * max(len(self.a), 1) + ei)
        n = max(len(self.a), 1)
        return key // n, key % n


def _csr(
    key: NDArray[np.int64], val: NDArray[np.int64], n: int
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """CSR arrays ``(ptr (n + 1,), idx)`` of the values grouped by key ``0..n-1``."""
    o = np.argsort(key, kind="stable")
    ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(key, minlength=n), out=ptr[1:])
    return ptr, val[o].astype(np.int64)


def _obstacle_runs(neighbours: list[int]) -> int:
    """Number of cyclic runs of ``-1`` (obstacle) in a vertex's neighbour list."""
    if not neighbours:
        return 0
    n = len(neighbours)
    return sum(1 for k in range(n) if neighbours[k] == -1 and neighbours[k - 1] != -1) or (
        1 if all(x == -1 for x in neighbours) else 0
    )
