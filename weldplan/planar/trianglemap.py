"""The triangular-mesh map of paper 002 (section 2) as data: nodes, triangles, the weighted edge
graph, shortest paths along mesh edges, and the funnel that pulls a mesh path tight in its
triangle corridor. :mod:`weldplan.planar.meshmap` builds these maps (and re-exports
:class:`TriangleMap`); its docstring gives the paper's equations.
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

from weldplan.errors import PlanningError

log = logging.getLogger(__name__)


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
        corner = None
        if area2(apex, right, rgt) <= 0.0:  # the right side tightens
            if apex == right or area2(apex, left, rgt) > 0.0:
                right, ir = rgt, i
            else:  # it crosses the left side: the left end is a corner of the path
                corner = left, il
        if corner is None and area2(apex, left, lft) >= 0.0:  # the left side tightens
            if apex == left or area2(apex, right, lft) < 0.0:
                left, il = lft, i
            else:  # it crosses the right side: the right end is a corner
                corner = right, ir
        if corner is None:
            i += 1
            continue
        apex, ia = corner  # restart the funnel from the corner
        if out[-1] != apex:
            out.append(apex)
            where.append(ia)
        left = right = apex
        il = ir = ia
        i = ia + 1
    if out[-1] != L[-1]:
        out.append(L[-1])
        where.append(n - 1)
    return out, where
