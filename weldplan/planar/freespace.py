"""The free space of a planar scenario as a triangle mesh, and the mesh queries the default
pipeline's repair and polish stages need (:mod:`weldplan.planar.pipeline`).

The mesh is :func:`weldplan.planar.meshmap.triangulate_map` of the scenario (paper 002's
triangulation, Shewchuk's Triangle) with two choices of ours: circles are cut into
circumscribed regular polygons of :data:`CIRCLE_SIDES` sides (as the exact baseline's
visibility graph does; a path taut against the polygon is at most ``1/cos(pi/n) - 1``, 0.03 %,
longer along the stretch where it wraps the circle), and no maximum edge length (Triangle's
30 degree quality mesh of the outlines alone), since the funnel makes paths taut whatever the
size of the triangles. Start and goal are its first two terminals.

The mesh is a model of the free space for planning only: what the stages produce is judged
by :class:`~weldplan.geometry.obstacles2d.Obstacles2D`, never by the mesh.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix, csr_matrix
from scipy.sparse.csgraph import dijkstra

from weldplan.errors import PlanningError
from weldplan.geometry.obstacles2d import Obstacles2D, grid_to_rectangles
from weldplan.planar.meshmap import TriangleMap, triangulate_map
from weldplan.planar.scenarios import Scenario

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: sides of the circumscribed polygons that stand for circles in the mesh (the exact
#: baseline's visibility graph uses the same number, ``weldplan.planar.exact.CIRCLE_SIDES``)
CIRCLE_SIDES = 128
#: relative growth of circles before they are cut into polygons, so that polygon sides
#: tangent to a circle do not graze it by rounding
CIRCLE_PAD = 1e-6
#: tolerance (relative to the map size) of the point-in-triangle and segment-triangle tests
MESH_TOL = 1e-9
#: segment x triangle pairs tested per chunk
PAIR_CHUNK = 4_000_000


@dataclass(frozen=True, eq=False)
class FreeSpaceMesh:
    """A scenario's free space as a triangle mesh, with point location and corridors.

    Attributes
    ----------
    mesh
        The triangulation; ``mesh.terminals[:2]`` are the start and goal nodes.
    blocked
        ``(m,) bool``: nodes no path may pass through: pinch points of the obstacles (where two
        obstacles touch at a point, :meth:`Obstacles2D.pinch_points`).
    """

    mesh: TriangleMap
    blocked: NDArray[np.bool_]

    @property
    def start_node(self) -> int:
        return int(self.mesh.terminals[0])

    @property
    def goal_node(self) -> int:
        return int(self.mesh.terminals[1])

    @cached_property
    def scale(self) -> float:
        return float(np.ptp(self.mesh.nodes, axis=0).max()) or 1.0

    @cached_property
    def tri_points(self) -> FloatArray:
        """``(k, 3, 2)``: the counter-clockwise corners of every triangle."""
        return self.mesh.nodes[self.mesh.ccw_cells]

    @cached_property
    def boundary_edges(self) -> tuple[FloatArray, FloatArray]:
        """Ends ``(b, 2), (b, 2)`` of the outline edges (sides of one triangle only)."""
        T = self.mesh.ccw_cells
        e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
        n = self.mesh.n_nodes
        lone = ~np.isin(e[:, 0] * n + e[:, 1], e[:, 1] * n + e[:, 0])
        P = self.mesh.nodes
        return P[e[lone, 0]], P[e[lone, 1]]

    @cached_property
    def graph(self) -> csr_matrix:
        """Edge graph with the blocked nodes cut out."""
        m = self.mesh
        ok = ~(self.blocked[m.edge_t] | self.blocked[m.edge_s])
        return _sym_graph(m.edge_t[ok], m.edge_s[ok], m.edge_d[ok], m.n_nodes)

    def locate(self, points: ArrayLike) -> NDArray[np.int64]:
        """Triangle containing each point ``(n, 2)`` (closed, within :data:`MESH_TOL`), or -1."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        T = self.tri_points
        tol = MESH_TOL * self.scale
        out = np.full(len(P), -1, dtype=np.int64)
        step = max(1, PAIR_CHUNK // max(1, len(T)))
        for s in range(0, len(P), step):
            Q = P[s : s + step]
            inside = np.ones((len(Q), len(T)), dtype=bool)
            for k in range(3):
                a, b = T[:, k], T[:, (k + 1) % 3]
                e = b - a
                L = np.hypot(e[:, 0], e[:, 1])
                c = e[:, 0] * (Q[:, None, 1] - a[:, 1]) - e[:, 1] * (Q[:, None, 0] - a[:, 0])
                inside &= c >= -tol * L
            hit = inside.any(axis=1)
            out[s : s + len(Q)] = np.where(hit, inside.argmax(axis=1), -1)
        return out

    def crosses_outline(self, A: ArrayLike, B: ArrayLike) -> NDArray[np.bool_]:
        """Whether segments ``A -> B (n, 2)`` properly cross an outline edge: ``(n,) bool``.

        Touching an outline at a point (a corner, as taut paths do) is not a crossing.
        """
        A = np.asarray(A, dtype=np.float64).reshape(-1, 2)
        B = np.asarray(B, dtype=np.float64).reshape(-1, 2)
        C, D = self.boundary_edges
        tol = MESH_TOL * self.scale

        def side(p: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
            # signed distance-like cross product of r against the line p -> q, scaled by |pq|
            d = q - p
            L = np.maximum(np.hypot(d[..., 0], d[..., 1]), 1e-300)
            return (d[..., 0] * (r[..., 1] - p[..., 1]) - d[..., 1] * (r[..., 0] - p[..., 0])) / L

        out = np.zeros(len(A), dtype=bool)
        step = max(1, PAIR_CHUNK // max(1, len(C)))
        for s in range(0, len(A), step):
            a, b = A[s : s + step, None], B[s : s + step, None]
            s1, s2 = side(a, b, C[None]), side(a, b, D[None])
            s3, s4 = side(C[None], D[None], a), side(C[None], D[None], b)
            cross = ((s1 > tol) & (s2 < -tol) | (s1 < -tol) & (s2 > tol)) & (
                (s3 > tol) & (s4 < -tol) | (s3 < -tol) & (s4 > tol)
            )
            out[s : s + step] = cross.any(axis=1)
        return out

    def corridor(self, path: ArrayLike) -> NDArray[np.bool_]:
        """``(k,) bool``: the triangles a polyline ``(n, 2)`` meets (separating-axis test on
        every segment x triangle pair, within :data:`MESH_TOL`)."""
        P = np.asarray(path, dtype=np.float64).reshape(-1, 2)
        A, B = P[:-1], P[1:]
        T = self.tri_points
        tol = MESH_TOL * self.scale
        lo_t, hi_t = T.min(axis=1), T.max(axis=1)
        lo_s, hi_s = np.minimum(A, B), np.maximum(A, B)
        out = np.zeros(len(T), dtype=bool)
        step = max(1, PAIR_CHUNK // max(1, len(T)))
        for s in range(0, len(A), step):
            sl = slice(s, s + step)
            box = np.all(
                (lo_s[sl, None] <= hi_t[None] + tol) & (hi_s[sl, None] >= lo_t[None] - tol),
                axis=-1,
            )
            si, ti = np.nonzero(box)
            si = si + s
            a, b, tri = A[si], B[si], T[ti]
            sep = np.zeros(len(si), dtype=bool)
            # axes: the three triangle edge normals and the segment's normal
            axes = [tri[:, (k + 1) % 3] - tri[:, k] for k in range(3)] + [b - a]
            for d in axes:
                nrm = np.stack([-d[:, 1], d[:, 0]], axis=1)
                L = np.hypot(nrm[:, 0], nrm[:, 1])
                ok = L > 0
                nrm = nrm / np.where(ok, L, 1.0)[:, None]
                pt = np.einsum("nkj,nj->nk", tri, nrm)
                ps = np.stack([np.sum(a * nrm, 1), np.sum(b * nrm, 1)], axis=1)
                gap = (pt.min(1) > ps.max(1) + tol) | (ps.min(1) > pt.max(1) + tol)
                sep |= ok & gap
            out[ti[~sep]] = True
        return out

    def route(self, a: ArrayLike, b: ArrayLike) -> FloatArray:
        """A path ``(p, 2)`` along mesh edges from free point ``a`` to free point ``b``: each end
        joined to the corners of its triangle (visible from it: triangles are convex and
        free), Dijkstra between them over :attr:`graph`.

        Raises
        ------
        PlanningError
            When ``a`` or ``b`` is not in the mesh or ``b`` cannot be reached from ``a``.
        """
        pa, pb = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
        ta, tb = self.locate(np.stack([pa, pb]))
        if ta < 0 or tb < 0:
            raise PlanningError("a repair end lies outside the free-space mesh")
        if ta == tb:
            return np.stack([pa, pb])
        m = self.mesh.n_nodes
        ca, cb = self.mesh.cells[ta], self.mesh.cells[tb]
        P = self.mesh.nodes
        ia = np.full(3, m)
        ib = np.full(3, m + 1)
        w_a = np.linalg.norm(P[ca] - pa, axis=1)
        w_b = np.linalg.norm(P[cb] - pb, axis=1)
        g = self.graph.tocoo()
        rows = np.concatenate([g.row, ia, ca, ib, cb])
        cols = np.concatenate([g.col, ca, ia, cb, ib])
        w = np.concatenate([g.data, w_a, w_a, w_b, w_b])
        # zero-length joins (an end on a mesh node) would vanish from the sparse matrix
        w = np.maximum(w, 1e-300)
        G = coo_matrix((w, (rows, cols)), shape=(m + 2, m + 2)).tocsr()
        dist, pred = dijkstra(G, directed=True, indices=m, return_predecessors=True)
        if not np.isfinite(dist[m + 1]):
            raise PlanningError("the repair cannot reach the next free point")
        order = [m + 1]
        while order[-1] != m:
            order.append(int(pred[order[-1]]))
        inner = [v for v in order[::-1] if v < m]
        return np.concatenate([pa[None], P[inner], pb[None]])

    def corridor_nodes(self, path: ArrayLike) -> NDArray[np.int64]:
        """The shortest mesh-edge node path from the start node to the goal node inside the
        triangles that ``path`` meets (:meth:`corridor`), blocked nodes excepted.

        Raises
        ------
        PlanningError
            When the corridor does not join start and goal (the path leaves the mesh).
        """
        keep = self.corridor(path)
        T = self.mesh.cells[keep]
        e = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
        e = np.unique(np.sort(e, axis=1), axis=0)
        e = e[~(self.blocked[e[:, 0]] | self.blocked[e[:, 1]])]
        P = self.mesh.nodes
        d = np.maximum(np.linalg.norm(P[e[:, 0]] - P[e[:, 1]], axis=1), 1e-300)
        G = _sym_graph(e[:, 0], e[:, 1], d, self.mesh.n_nodes)
        s, g = self.start_node, self.goal_node
        dist, pred = dijkstra(G, directed=False, indices=s, return_predecessors=True)
        if not np.isfinite(dist[g]):
            raise PlanningError("the path's corridor of triangles does not join start and goal")
        return self.mesh.path_nodes(pred, g)


def _sym_graph(i: NDArray, j: NDArray, w: NDArray, n: int) -> csr_matrix:
    return coo_matrix(
        (np.concatenate([w, w]), (np.concatenate([i, j]), np.concatenate([j, i]))), shape=(n, n)
    ).tocsr()


_MESH_CACHE: dict[tuple[str, str], FreeSpaceMesh] = {}


def free_space_mesh(scenario: Scenario) -> FreeSpaceMesh:
    """The :class:`FreeSpaceMesh` of ``scenario`` (cached per scenario file).

    Raises
    ------
    PlanningError
        When start or goal is not in the free space.
    """
    key = (str(scenario.path), scenario.name)
    if key in _MESH_CACHE:
        return _MESH_CACHE[key]
    obs, grid = scenario.obstacles, scenario.grid
    rect = np.asarray(obs.rectangles).reshape(-1, 4)
    if grid is not None:  # the grid's outline, not its (touching) row rectangles
        gr = grid_to_rectangles(grid.occupied, grid.origin, grid.cell)
        rect = rect[~(rect[:, None, :] == gr[None]).all(-1).any(-1)]
    circles = np.asarray(obs.circles, dtype=np.float64).reshape(-1, 3).copy()
    circles[:, 2] *= 1.0 + CIRCLE_PAD
    polys = Obstacles2D(circles=circles).as_polygons(CIRCLE_SIDES).polygons
    cut = Obstacles2D(rectangles=rect, polygons=(*obs.polygons, *polys))
    pts = np.stack([scenario.start, scenario.goal])
    mesh = triangulate_map(cut, scenario.bounds, math.inf, points=pts, grid=grid)
    pinch = scenario.world.pinch_points()
    blocked = np.zeros(mesh.n_nodes, dtype=bool)
    if len(pinch):
        d = np.linalg.norm(mesh.nodes[:, None] - pinch[None], axis=-1).min(axis=1)
        blocked = d <= MESH_TOL * float(np.ptp(mesh.nodes, axis=0).max())
    blocked[mesh.terminals] = False
    out = FreeSpaceMesh(mesh=mesh, blocked=blocked)
    log.debug(
        "free-space mesh of %s: %d nodes, %d triangles", scenario.name, mesh.n_nodes, mesh.n_cells
    )
    _MESH_CACHE[key] = out
    return out
