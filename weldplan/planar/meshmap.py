"""Triangular-mesh maps (paper 002, section 2): free space cut into triangles, and shortest paths
over the edges of the mesh.

The map is triangulated by Shewchuk's Triangle (the ``triangle`` package from PyPI), a
constrained Delaunay triangulation with the obstacle outlines and the map frame as segments and a
maximum triangle area derived from the maximum edge length ``M`` (the area of the equilateral
triangle of side ``M``, ``sqrt(3) / 4 M^2``, with Triangle's 30 degree minimum-angle quality
switch), after splitting every input segment into pieces no longer than ``M``. Triangles whose
centroid lies in an obstacle (or outside the map) are dropped.

Paper 002 stores the mesh as a node matrix ``N`` (eq. 9: one column per node; the paper keeps a
third, z row that is zero on a planar map, dropped here) and a connection matrix ``C``
(eq. 10: the three node numbers of each triangle), assembles the node association vectors ``T``
and ``S`` (eqs. 11-12: the two ends of each mesh edge) and their lengths ``D`` (eq. 13), and
plans on the weighted graph they form. :class:`TriangleMap` keeps exactly these (as rows:
``nodes (m, 2)``, ``cells (k, 3)``, ``edge_t``, ``edge_s``, ``edge_d``), exposes the graph as a
:mod:`networkx` graph and answers shortest-path queries with Dijkstra on the same edges (scipy's
compiled Dijkstra, the same answer as networkx and about two orders of magnitude faster on the
thousands-of-nodes meshes of Table 3).

Paper 002's rule for ``M``: it must stay below a quarter of the smallest gap between two
obstacles, so that a path can pass between any two (:func:`max_edge_rule`). Mesh paths follow
triangle edges, so they are never shorter than the any-angle optimum (the visibility graph of
:mod:`weldplan.planar.exact`) and approach it as ``M`` shrinks.

Polyanya navigation meshes (``.mesh`` v2, read by :class:`weldplan.planar.exact.MeshFreeSpace`)
are used the same way: their boundary edges become the segments of the triangulation.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import dijkstra

from weldplan.errors import InputError, PlanningError
from weldplan.geometry.obstacles2d import Obstacles2D

log = logging.getLogger(__name__)

#: Triangle's minimum-angle quality bound in degrees (the ``q`` switch); keeps edges near ``M``
MIN_ANGLE = 30.0
#: circles become circumscribed polygons with sides no longer than ``M``, at least this many
MIN_CIRCLE_SIDES = 16
#: and at most this many
MAX_CIRCLE_SIDES = 256
#: relative margin on circumscribed circle polygons: their sides touch the circle at their
#: midpoints, which an exact collision check would count as grazing
CIRCLE_PAD = 1e-6
#: triangle centroids x obstacle edges tested per chunk by the free-space filter
KEEP_CHUNK = 2_000_000


@dataclass(frozen=True, eq=False)
class TriangleMap:
    """A triangulated free space and its edge graph (paper 002, eqs. 9-13).

    Attributes
    ----------
    nodes
        ``(m, 2) float``: node coordinates, the node matrix N (eq. 9) as rows.
    cells
        ``(k, 3) int``: node numbers of each triangle, the connection matrix C (eq. 10) as rows.
    edge_t, edge_s
        ``(n,) int``: the two ends of each undirected mesh edge, T and S (eqs. 11-12).
    edge_d
        ``(n,) float``: edge lengths, D (eq. 13).
    max_edge
        The requested maximum edge length ``M`` (``inf`` for a mesh taken as it is).
    terminals
        ``(t,) int``: node numbers of the points inserted as mesh vertices (start and goals).
    """

    nodes: NDArray[np.float64]
    cells: NDArray[np.int64]
    edge_t: NDArray[np.int64]
    edge_s: NDArray[np.int64]
    edge_d: NDArray[np.float64]
    max_edge: float
    terminals: NDArray[np.int64]

    @property
    def n_nodes(self) -> int:
        return int(len(self.nodes))

    @property
    def n_cells(self) -> int:
        return int(len(self.cells))

    @property
    def longest_edge(self) -> float:
        return float(self.edge_d.max()) if len(self.edge_d) else 0.0

    @cached_property
    def csgraph(self) -> csr_matrix:
        """The symmetric sparse adjacency matrix of edge lengths ``(m, m)``."""
        m = self.n_nodes
        i = np.concatenate([self.edge_t, self.edge_s])
        j = np.concatenate([self.edge_s, self.edge_t])
        w = np.concatenate([self.edge_d, self.edge_d])
        return coo_matrix((w, (i, j)), shape=(m, m)).tocsr()

    @cached_property
    def graph(self) -> Any:
        """The weighted undirected :class:`networkx.Graph` (node attribute ``pos``, edge
        attribute ``weight``)."""
        import networkx as nx

        g = nx.Graph()
        g.add_nodes_from((k, {"pos": (float(x), float(y))}) for k, (x, y) in enumerate(self.nodes))
        g.add_weighted_edges_from(
            zip(self.edge_t.tolist(), self.edge_s.tolist(), self.edge_d.tolist(), strict=True)
        )
        return g

    def nearest_node(self, points: ArrayLike) -> NDArray[np.int64]:
        """Node numbers ``(...)`` nearest to points ``(..., 2)``."""
        P = np.asarray(points, dtype=np.float64)
        d = np.linalg.norm(P[..., None, :] - self.nodes, axis=-1)
        return np.argmin(d, axis=-1)

    def distances(
        self, sources: ArrayLike, targets: ArrayLike | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Shortest-path lengths along mesh edges.

        Parameters
        ----------
        sources
            ``(a,)`` node numbers.
        targets
            ``(b,)`` node numbers (default: ``sources``).

        Returns
        -------
        dist
            ``(a, b)``: lengths (``inf`` where unreachable).
        pred
            ``(a, m)``: Dijkstra predecessors from each source (``-9999`` at the source and
            unreachable nodes), for :meth:`path_nodes`.
        """
        src = np.asarray(sources, dtype=np.int64).reshape(-1)
        tgt = src if targets is None else np.asarray(targets, dtype=np.int64).reshape(-1)
        dist, pred = dijkstra(self.csgraph, directed=False, indices=src, return_predecessors=True)
        return dist[:, tgt], pred

    def path_nodes(self, pred_row: NDArray[np.int64], target: int) -> NDArray[np.int64]:
        """Node numbers from the source of ``pred_row`` (a row of :meth:`distances`' ``pred``)
        to ``target``."""
        out = [int(target)]
        while pred_row[out[-1]] >= 0:
            out.append(int(pred_row[out[-1]]))
        return np.array(out[::-1], dtype=np.int64)

    @cached_property
    def ccw_cells(self) -> NDArray[np.int64]:
        """``(k, 3) int``: :attr:`cells` with every triangle in counter-clockwise order."""
        T = self.cells
        P = self.nodes[T]
        cross = (P[:, 1, 0] - P[:, 0, 0]) * (P[:, 2, 1] - P[:, 0, 1]) - (
            P[:, 1, 1] - P[:, 0, 1]
        ) * (P[:, 2, 0] - P[:, 0, 0])
        out = np.where((cross < 0)[:, None], T[:, [0, 2, 1]], T)
        out.setflags(write=False)
        return out

    @cached_property
    def _ccw_tuples(self) -> list[tuple[int, int, int]]:
        return [tuple(t) for t in self.ccw_cells.tolist()]  # type: ignore[misc]

    @cached_property
    def half_edges(self) -> dict[tuple[int, int], int]:
        """``(a, b) -> triangle`` for every directed side ``a -> b`` of a counter-clockwise
        triangle (:attr:`ccw_cells`): the triangle to the left of ``a -> b``."""
        T = self.ccw_cells
        a, b, c = T[:, 0].tolist(), T[:, 1].tolist(), T[:, 2].tolist()
        k = range(len(T))
        out: dict[tuple[int, int], int] = {}
        for u, v in ((a, b), (b, c), (c, a)):
            out.update(zip(zip(u, v, strict=True), k, strict=True))
        return out

    @cached_property
    def boundary_nodes(self) -> NDArray[np.bool_]:
        """``(m,) bool``: nodes on the outline of the free space (an obstacle or the frame)."""
        T = self.ccw_cells
        e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
        key = e[:, 0] * self.n_nodes + e[:, 1]
        twin = e[:, 1] * self.n_nodes + e[:, 0]
        lone = ~np.isin(key, twin)
        out = np.zeros(self.n_nodes, dtype=bool)
        out[e[lone].reshape(-1)] = True
        out.setflags(write=False)
        return out

    def funnel(self, path: ArrayLike, *, max_rounds: int = 1000) -> NDArray[np.float64]:
        """The shortest path homotopic to a mesh-edge path (string pulling on the mesh).

        1. Corridor: at every inner node ``v_i`` of the node path, the fan of triangles around
           ``v_i`` between the edges to ``v_(i-1)`` and ``v_(i+1)``, on the side of the smaller
           angle that is free all the way (at an obstacle corner only one side is). The node
           path lies on the corridor's outline, so the taut path is never longer than it.
        2. Mononen's simple stupid funnel algorithm (Lee and Preparata's funnel, 1984) over the
           portals of the corridor (the sides shared by consecutive triangles) gives the
           shortest path inside it.
        3. A corridor may wrap around a mesh node in free space (a Steiner point of the
           refined mesh) as if it were an obstacle: where the taut path bends at such a node,
           the corridor is rerouted around the node's other side, back-and-forth steps are
           cancelled, and step 2 runs again, until the path bends only at outline nodes. Then
           the corridor holds the shortest path homotopic to the node path, and the result is
           that path (the any-angle optimum when the node path goes around the obstacles on
           the optimal sides).

        A node where neither side is free (two obstacles touching at a point) is kept as a
        waypoint and the corridor restarts there.

        Parameters
        ----------
        path
            ``(p,)`` node numbers of a path along mesh edges (:meth:`path_nodes`).
        max_rounds
            Cap on the reroutings of step 3 per corridor.

        Returns
        -------
        ``(q, 2)``: the taut path, from ``nodes[path[0]]`` to ``nodes[path[-1]]``; its inner
        points are mesh nodes.
        """
        v = [int(x) for x in np.asarray(path, dtype=np.int64).reshape(-1)]
        if len(v) <= 2:
            return self.nodes[np.asarray(v, dtype=np.int64)]
        out = [v[0]]
        first = 0  # node-path index where the current corridor starts
        tris: list[int] = []
        for i in range(1, len(v) - 1):
            fan = self._fan(v[i - 1], v[i], v[i + 1])
            if fan is None:  # a pinch point: the path must pass through v_i
                if not tris:  # the corridor is the single edge v_(i-1) v_i
                    out.append(v[i])
                else:
                    out += self._taut(v[first], v[i], tris, max_rounds)[1:]
                first, tris = i, []
                continue
            for t in fan:
                if not tris or tris[-1] != t:
                    tris.append(t)
        if not tris:  # the last step is a single edge after a pinch point
            tris = [self.half_edges.get((v[-2], v[-1]), self.half_edges.get((v[-1], v[-2])))]
        out += self._taut(v[first], v[-1], tris, max_rounds)[1:]
        return self.nodes[np.array(out, dtype=np.int64)]

    def _fan(self, u: int, v: int, w: int) -> list[int] | None:
        """Triangles around ``v`` from the one beside edge ``u v`` to the one beside ``v w``:
        on the side of the smaller angle when both sides are free, else the free one, or
        ``None`` when neither side is free all the way."""
        he = self.half_edges
        T = self._ccw_tuples
        walks: dict[int, list[int] | None] = {}
        for side in (-1, 1):  # -1: counter-clockwise around v, +1: clockwise
            tri: list[int] = []
            c = u
            ok = False
            while True:
                t = he.get((v, c) if side < 0 else (c, v))
                if t is None:
                    break
                tri.append(t)
                x = sum(T[t]) - v - c  # the third vertex
                if x == w:
                    ok = True
                    break
                c = x
                if len(tri) > len(T):  # pragma: no cover - an inconsistent mesh
                    break
            walks[side] = tri if ok else None
        free = [s for s in (-1, 1) if walks[s] is not None]
        if not free:
            return None
        side = free[0]
        if len(free) == 2:
            P = self.nodes
            a, b = P[u] - P[v], P[w] - P[v]
            ccw = math.atan2(a[0] * b[1] - a[1] * b[0], a @ b) % (2 * math.pi)  # u -> w, ccw
            side = -1 if ccw <= math.pi else 1
        return walks[side]

    def _portals(self, start: int, end: int, tris: list[int]) -> tuple[list[int], list[int]]:
        """Left and right ends of the portals of a triangle corridor, the two ends first and
        last (degenerate portals)."""
        T = self._ccw_tuples
        L, R = [start], [start]
        for t0, t1 in zip(tris[:-1], tris[1:], strict=True):
            a, b, c = T[t0]
            shared = T[t1]
            # the side of t0 (counter-clockwise a -> b) that t1 shares; leaving t0 across it,
            # its end b is on the traveller's left
            for p, q in ((a, b), (b, c), (c, a)):
                if p in shared and q in shared:
                    L.append(q)
                    R.append(p)
                    break
        L.append(end)
        R.append(end)
        return L, R

    def _taut(self, start: int, end: int, tris: list[int], max_rounds: int) -> list[int]:
        """Funnel through the corridor ``tris`` from node ``start`` to node ``end``, rerouting
        it around free-space nodes the path bends at (see :meth:`funnel`)."""
        he = self.half_edges
        T = self._ccw_tuples
        border = self.boundary_nodes
        tris = _cancel_backtracks(tris)
        for _ in range(max_rounds):
            L, R = self._portals(start, end, tris)
            nodes, where = _funnel(self.nodes, L, R)
            free = [k for k in range(1, len(nodes) - 1) if not border[nodes[k]]]
            if not free:
                return nodes
            # reroute every bend at a free node whose run of triangles does not overlap an
            # earlier one, from the back so that indices stay valid
            runs: list[tuple[int, int, list[int]]] = []
            for k in free:
                v, pi = nodes[k], where[k]
                # the run of corridor triangles around v, through portal pi (between
                # tris[pi - 1] and tris[pi])
                a = b = min(max(pi, 0), len(tris) - 1)
                while a > 0 and v in T[tris[a - 1]]:
                    a -= 1
                while b < len(tris) - 1 and v in T[tris[b + 1]]:
                    b += 1
                if a == b or (runs and a <= runs[-1][1]):
                    continue
                ta = T[tris[a]]
                i = ta.index(v)
                p, q = ta[(i + 1) % 3], ta[(i + 2) % 3]  # ta = (v, p, q) counter-clockwise
                step_ccw = he.get((v, q)) != tris[a + 1]  # the other way round v
                run = [tris[a]]
                c = q if step_ccw else p
                while run[-1] != tris[b]:
                    t = he.get((v, c) if step_ccw else (c, v))
                    if t is None or len(run) > len(T):  # pragma: no cover - free nodes' stars
                        run = []
                        break
                    run.append(t)
                    c = sum(T[t]) - v - c
                if run:
                    runs.append((a, b, run))
            if not runs:  # pragma: no cover
                return nodes
            for a, b, run in reversed(runs):
                tris = tris[:a] + run + tris[b + 1 :]
            tris = _cancel_backtracks(tris)
        log.debug("funnel: %d reroutings were not enough", max_rounds)
        return nodes

    def shortest_path(self, a: int, b: int) -> tuple[NDArray[np.float64], float]:
        """The shortest mesh path between nodes ``a`` and ``b``: points ``(p, 2)`` and length.

        Raises
        ------
        PlanningError
            When ``b`` cannot be reached from ``a``.
        """
        dist, pred = self.distances([a], [b])
        if not np.isfinite(dist[0, 0]):
            raise PlanningError(f"mesh node {b} cannot be reached from node {a}")
        return self.nodes[self.path_nodes(pred[0], b)], float(dist[0, 0])


def _cancel_backtracks(tris: list[int]) -> list[int]:
    """A triangle corridor with every immediate return (``t, u, t``) cancelled."""
    out: list[int] = []
    for t in tris:
        if len(out) >= 2 and out[-2] == t:
            out.pop()
        elif not out or out[-1] != t:
            out.append(t)
    return out


def _funnel(P: NDArray[np.float64], L: list[int], R: list[int]) -> tuple[list[int], list[int]]:
    """Mononen's simple stupid funnel over portals ``(L[i], R[i])`` (node numbers; the first
    and last portals are the two ends). Returns the node numbers of the shortest path through
    the portals and, for each, the portal index it came from."""

    def area2(a: int, b: int, c: int) -> float:
        # twice the signed area of (a, b, c), negated: > 0 when c is right of a -> b
        ax, ay = P[b, 0] - P[a, 0], P[b, 1] - P[a, 1]
        bx, by = P[c, 0] - P[a, 0], P[c, 1] - P[a, 1]
        return float(bx * ay - ax * by)

    apex = left = right = L[0]
    ia = il = ir = 0
    out, where = [apex], [0]
    i, n = 1, len(L)
    while i < n:
        lft, rgt = L[i], R[i]
        if area2(apex, right, rgt) <= 0.0:  # the right side tightens
            if apex == right or area2(apex, left, rgt) > 0.0:
                right, ir = rgt, i
            else:  # it crosses the left side: the left end is a corner of the path
                apex, ia = left, il
                if out[-1] != apex:
                    out.append(apex)
                    where.append(ia)
                left = right = apex
                il = ir = ia
                i = ia + 1
                continue
        if area2(apex, left, lft) >= 0.0:  # the left side tightens
            if apex == left or area2(apex, right, lft) < 0.0:
                left, il = lft, i
            else:
                apex, ia = right, ir
                if out[-1] != apex:
                    out.append(apex)
                    where.append(ia)
                left = right = apex
                il = ir = ia
                i = ia + 1
                continue
        i += 1
    if out[-1] != L[-1]:
        out.append(L[-1])
        where.append(n - 1)
    return out, where


def max_edge_rule(obstacles: Obstacles2D, *, circle_sides: int = 64) -> float:
    """Paper 002's bound on ``M`` (sec. 2.2): a quarter of the smallest gap between two obstacles.

    The gap between two obstacles is the smallest distance between their outlines (circles as
    circumscribed ``circle_sides``-gons); obstacles that touch or overlap count as one and are
    skipped. Returns ``inf`` with fewer than two separate obstacles.
    """
    polys = _obstacle_polygons(obstacles, circle_sides=circle_sides)
    best = math.inf
    for a in range(len(polys)):
        for b in range(a + 1, len(polys)):
            g = _polygon_gap(polys[a], polys[b])
            if g > 0:
                best = min(best, g)
    return best / 4.0


def _polygon_gap(P: NDArray[np.float64], Q: NDArray[np.float64]) -> float:
    """Distance between two polygon outlines (0 when their outlines cross or one holds the
    other's vertex)."""
    from weldplan.geometry.obstacles2d import point_segment_distance

    Pa, Pb = P, np.roll(P, -1, axis=0)
    Qa, Qb = Q, np.roll(Q, -1, axis=0)
    d1 = point_segment_distance(P[:, None, :], Qa[None], Qb[None]).min()
    d2 = point_segment_distance(Q[:, None, :], Pa[None], Pb[None]).min()
    d = float(min(d1, d2))
    if d > 0:
        inside = (
            Obstacles2D(polygons=(P,)).contains(Q).any()
            or Obstacles2D(polygons=(Q,)).contains(P).any()
        )
        if inside:
            return 0.0
    return d


def _obstacle_polygons(
    obstacles: Obstacles2D, *, circle_sides: int | None = None, max_edge: float = math.inf
) -> list[NDArray[np.float64]]:
    """Every obstacle as a polygon ``(v, 2)``: rectangles as 4-gons, circles as circumscribed
    regular polygons (``circle_sides`` sides, or enough for sides of at most ``max_edge``)."""
    out: list[NDArray[np.float64]] = [np.asarray(p, dtype=np.float64) for p in obstacles.polygons]
    for x0, y0, x1, y1 in np.asarray(obstacles.rectangles).reshape(-1, 4):
        out.append(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=np.float64))
    for cx, cy, r in np.asarray(obstacles.circles).reshape(-1, 3):
        if circle_sides is not None:
            n = int(circle_sides)
        else:
            # side of the circumscribed n-gon: 2 r tan(pi / n) <= M
            n = MIN_CIRCLE_SIDES
            if np.isfinite(max_edge):
                n = max(n, int(math.ceil(math.pi / math.atan(max_edge / (2 * r)))))
            n = min(n, MAX_CIRCLE_SIDES)
        R = r / math.cos(math.pi / n) * (1.0 + CIRCLE_PAD)
        th = 2 * math.pi * np.arange(n) / n
        out.append(np.stack([cx + R * np.cos(th), cy + R * np.sin(th)], axis=1))
    return out


def _split_segments(
    a: NDArray[np.float64], b: NDArray[np.float64], max_edge: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Points and segment index pairs of the segments ``a -> b`` (``(s, 2)`` each), each cut
    into pieces no longer than ``max_edge``."""
    pts: list[NDArray[np.float64]] = []
    segs: list[NDArray[np.int64]] = []
    base = 0
    L = np.linalg.norm(b - a, axis=1)
    pieces = np.ones(len(a), dtype=np.int64)
    if np.isfinite(max_edge):
        pieces = np.maximum(1, np.ceil(L / max_edge - 1e-9).astype(np.int64))
    for k in range(len(a)):
        n = int(pieces[k])
        t = np.linspace(0.0, 1.0, n + 1)[:, None]
        pts.append(a[k] + t * (b[k] - a[k]))
        idx = base + np.arange(n)
        segs.append(np.stack([idx, idx + 1], axis=1))
        base += n + 1
    if not pts:
        return np.zeros((0, 2)), np.zeros((0, 2), dtype=np.int64)
    return np.concatenate(pts), np.concatenate(segs)


def triangulate_segments(
    seg_a: ArrayLike,
    seg_b: ArrayLike,
    keep: Any,
    *,
    max_edge: float,
    points: ArrayLike | None = None,
    min_angle: float = MIN_ANGLE,
) -> TriangleMap:
    """Constrained Delaunay triangulation of the segments ``seg_a -> seg_b`` with Triangle.

    Parameters
    ----------
    seg_a, seg_b
        ``(s, 2)``: segment ends (obstacle outlines and the map frame); crossing segments are
        split by Triangle at their intersection.
    keep
        ``keep(centroids (k, 2)) -> (k,) bool``: which triangles are free space; or
        ``(r, 2)`` seed points, one inside each free region bounded by the segments (Triangle's
        regional attributes then mark the free triangles, in linear time).
    max_edge
        ``M``: input segments are split to at most ``M`` and triangles get at most the area of
        the equilateral triangle of side ``M`` (``inf``: no limit).
    points
        ``(t, 2)``: extra points made mesh vertices (start and goals); their node numbers are
        :attr:`TriangleMap.terminals`, in order.
    min_angle
        Triangle's quality bound in degrees (0 to switch it off).
    """
    try:
        import triangle as tr
    except ImportError as exc:  # pragma: no cover - a runtime dependency
        raise ImportError("triangular-mesh maps need the 'triangle' package") from exc
    A = np.asarray(seg_a, dtype=np.float64).reshape(-1, 2)
    B = np.asarray(seg_b, dtype=np.float64).reshape(-1, 2)
    V, S = _split_segments(A, B, max_edge)
    extra = np.zeros((0, 2)) if points is None else np.asarray(points, dtype=np.float64)
    extra = extra.reshape(-1, 2)
    verts = np.concatenate([extra, V])
    # merge duplicate vertices (shared polygon corners) so Triangle sees clean input
    scale = float(np.ptp(verts, axis=0).max()) or 1.0
    key = np.round(verts / (1e-9 * scale)).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    verts_u = verts[first]
    segs = inv[len(extra) + S]
    segs = segs[segs[:, 0] != segs[:, 1]]
    opts = "pzQ"
    seeds = None if callable(keep) else np.asarray(keep, dtype=np.float64).reshape(-1, 2)
    if seeds is not None:
        opts += "A"
    if min_angle > 0:
        opts += f"q{min_angle:g}"
    if np.isfinite(max_edge):
        opts += f"a{math.sqrt(3.0) / 4.0 * max_edge**2:.17g}"
    pslg: dict[str, Any] = {"vertices": verts_u, "segments": segs}
    if seeds is not None:
        pslg["regions"] = np.concatenate(
            [seeds, np.ones((len(seeds), 1)), np.zeros((len(seeds), 1))], axis=1
        )
    try:
        out = tr.triangulate(pslg, opts)
    except RuntimeError as exc:  # Triangle's own check: crossing or near-coincident input
        raise InputError(
            f"the map's outline cannot be triangulated ({exc}): obstacles or bounds that nearly "
            "touch (closer than floating point resolves) or overlap in a degenerate way"
        ) from exc
    nodes = np.asarray(out["vertices"], dtype=np.float64)
    tris = np.asarray(out["triangles"], dtype=np.int64)
    if seeds is not None:
        tris = tris[np.asarray(out["triangle_attributes"]).reshape(-1) == 1]
    else:
        cen = nodes[tris].mean(axis=1)
        step = max(1, KEEP_CHUNK // max(1, len(A)))  # keep() may cost (points x segments)
        kept = np.concatenate(
            [np.asarray(keep(cen[s : s + step]), dtype=bool) for s in range(0, len(cen), step)]
        )
        tris = tris[kept]
    # drop nodes no kept triangle uses, renumber
    used = np.zeros(len(nodes), dtype=bool)
    used[tris.reshape(-1)] = True
    term_old = inv[: len(extra)]
    if not np.all(used[term_old]):
        bad = np.nonzero(~used[term_old])[0]
        raise PlanningError(f"points {bad.tolist()} are not in the free space of the mesh")
    new = np.cumsum(used) - 1
    nodes = nodes[used]
    tris = new[tris]
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    e = np.unique(np.sort(e, axis=1), axis=0)
    d = np.linalg.norm(nodes[e[:, 0]] - nodes[e[:, 1]], axis=1)
    for arr in (nodes, tris, e, d):
        arr.setflags(write=False)
    tmap = TriangleMap(
        nodes=nodes,
        cells=tris,
        edge_t=e[:, 0].copy(),
        edge_s=e[:, 1].copy(),
        edge_d=d,
        max_edge=float(max_edge),
        terminals=new[term_old],
    )
    log.debug(
        "triangle map: %d nodes, %d cells, %d edges (M = %g, longest %g)",
        tmap.n_nodes,
        tmap.n_cells,
        len(d),
        max_edge,
        tmap.longest_edge,
    )
    return tmap


def grid_boundary_segments(
    occupied: NDArray[np.bool_], origin: tuple[float, float] = (0.0, 0.0), cell: float = 1.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The outline of an occupancy grid ``occupied (nx, ny)`` (cell ``(i, j)`` covers
    ``[x0 + i c, x0 + (i+1) c] x [y0 + j c, ...]``) as maximal axis-aligned segments between
    occupied and free cells: ``(a (s, 2), b (s, 2))``. Unlike the rectangles of a grid, these
    never overlap, which Triangle's quality refinement needs."""
    occ = np.asarray(occupied, dtype=bool)
    nx, ny = occ.shape
    x0, y0 = origin
    A: list[list[float]] = []
    B: list[list[float]] = []
    pad = np.zeros((nx + 2, ny + 2), dtype=bool)
    pad[1:-1, 1:-1] = occ

    def runs(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
        d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
        return list(
            zip(np.nonzero(d == 1)[0].tolist(), np.nonzero(d == -1)[0].tolist(), strict=True)
        )

    for j in range(ny + 1):  # horizontal edges at y = y0 + j c
        for s, e in runs(pad[1:-1, j] != pad[1:-1, j + 1]):
            A.append([x0 + s * cell, y0 + j * cell])
            B.append([x0 + e * cell, y0 + j * cell])
    for i in range(nx + 1):  # vertical edges at x = x0 + i c
        for s, e in runs(pad[i, 1:-1] != pad[i + 1, 1:-1]):
            A.append([x0 + i * cell, y0 + s * cell])
            B.append([x0 + i * cell, y0 + e * cell])
    return np.array(A).reshape(-1, 2), np.array(B).reshape(-1, 2)


def triangulate_map(
    obstacles: Obstacles2D,
    bounds: ArrayLike,
    max_edge: float,
    *,
    points: ArrayLike | None = None,
    min_angle: float = MIN_ANGLE,
    grid: Any = None,
) -> TriangleMap:
    """Triangulate the free space of a planar map (paper 002, sec. 2.1).

    Parameters
    ----------
    obstacles
        Circles, rectangles and polygons (circles as circumscribed polygons with sides of at most
        ``max_edge``, so mesh edges never cut a circle).
    bounds
        ``(xmin, ymin, xmax, ymax)``: the map frame.
    max_edge
        ``M``, the maximum triangle edge length (map units).
    points
        ``(t, 2)``: points to make mesh nodes (start and goals), see :attr:`TriangleMap.terminals`.
    grid
        An occupancy grid (:class:`weldplan.planar.scenarios.GridMap`) whose outline is added as
        segments (``obstacles`` must then not hold the grid's rectangles).

    Raises
    ------
    PlanningError
        When a point is not in the free space.
    """
    if not max_edge > 0:
        raise ValueError(f"max_edge must be positive, got {max_edge}")
    x0, y0, x1, y1 = (float(v) for v in np.asarray(bounds, dtype=np.float64).reshape(4))
    frame = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    polys = _obstacle_polygons(obstacles, max_edge=max_edge)
    rings = [frame, *polys]
    A = np.concatenate(rings)
    B = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    if grid is not None:
        ga, gb = grid_boundary_segments(grid.occupied, grid.origin, grid.cell)
        A, B = np.concatenate([A, ga]), np.concatenate([B, gb])
    # point-in-polygon by matplotlib's compiled Path test behind a bounding-box filter (centroids
    # are never on an outline: the outlines are triangle edges)
    from matplotlib.path import Path as MplPath

    solid = [(p, p.min(axis=0), p.max(axis=0), MplPath(p)) for p in polys]
    eps = 1e-9 * max(x1 - x0, y1 - y0)

    def keep(c: NDArray[np.float64]) -> NDArray[np.bool_]:
        ok = (
            (c[:, 0] > x0 - eps)
            & (c[:, 0] < x1 + eps)
            & (c[:, 1] > y0 - eps)
            & (c[:, 1] < y1 + eps)
        )
        for _poly, lo, hi, path in solid:
            m = ok & np.all(c >= lo, axis=1) & np.all(c <= hi, axis=1)
            if m.any():
                ok[m] &= ~path.contains_points(c[m])
        if grid is not None:
            ij = grid.cell_of(c)
            nx, ny = grid.shape
            inside = (ij[:, 0] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] >= 0) & (ij[:, 1] < ny)
            occ = np.zeros(len(c), dtype=bool)
            occ[inside] = grid.occupied[ij[inside, 0], ij[inside, 1]]
            ok &= ~occ
        return ok

    return triangulate_segments(A, B, keep, max_edge=max_edge, points=points, min_angle=min_angle)


def triangulate_navmesh(
    space: Any,
    max_edge: float = math.inf,
    *,
    points: ArrayLike | None = None,
    min_angle: float = MIN_ANGLE,
) -> TriangleMap:
    """A triangular-mesh map of a Polyanya navigation mesh
    (:class:`weldplan.planar.exact.MeshFreeSpace`): its boundary edges are the segments, its
    free space the triangles kept; ``max_edge`` refines it (``inf``: Triangle's quality mesh of
    the boundary alone)."""

    # one seed inside one (convex) navmesh polygon of each connected free region marks the free
    # triangles: Triangle floods from every seed, so a seed per polygon (35k on aurora) costs
    # minutes where one per region costs milliseconds
    from scipy.sparse.csgraph import connected_components

    nb = space.polygon_neighbours
    n = len(nb)
    rows = np.repeat(np.arange(n), [len(x) for x in nb])
    cols = np.concatenate([np.asarray(x, dtype=np.int64) for x in nb]) if n else rows
    ok = cols >= 0
    adj = coo_matrix((np.ones(int(ok.sum())), (rows[ok], cols[ok])), shape=(n, n))
    _, label = connected_components(adj, directed=False)
    _, first = np.unique(label, return_index=True)
    seeds = np.array([space.vertices_xy[space.polygon_vertices[p]].mean(axis=0) for p in first])
    return triangulate_segments(
        space.edge_a, space.edge_b, seeds, max_edge=max_edge, points=points, min_angle=min_angle
    )
