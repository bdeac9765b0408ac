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

The map itself, :class:`TriangleMap` (with the funnel), lives in
:mod:`weldplan.planar.trianglemap` and is importable from here; this module builds it.

Polyanya navigation meshes (``.mesh`` v2, read by :class:`weldplan.planar.exact.MeshFreeSpace`)
are used the same way: their boundary edges become the segments of the triangulation.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix

from weldplan.errors import InputError, PlanningError
from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.planar.trianglemap import TriangleMap

__all__ = [
    "CIRCLE_PAD",
    "KEEP_CHUNK",
    "MAX_CIRCLE_SIDES",
    "MIN_ANGLE",
    "MIN_CIRCLE_SIDES",
    "TriangleMap",
    "grid_boundary_segments",
    "max_edge_rule",
    "triangulate_map",
    "triangulate_navmesh",
    "triangulate_segments",
]

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
    extra = np.zeros((0, 2)) if points is None else np.asarray(points, dtype=np.float64)
    verts_u, segs, term_old = _planar_graph(A, B, extra.reshape(-1, 2), max_edge)
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
    return _triangle_map(nodes, tris, term_old, max_edge)


def _planar_graph(
    A: NDArray[np.float64], B: NDArray[np.float64], extra: NDArray[np.float64], max_edge: float
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """Triangle's input: the segments ``A -> B (s, 2)`` split to at most ``max_edge`` and the
    ``extra (t, 2)`` points, duplicate vertices (shared polygon corners) merged so Triangle
    sees clean input. Returns the vertices ``(v, 2)``, the segments ``(s', 2)`` as vertex
    pairs, and the vertex of each extra point ``(t,)``."""
    V, S = _split_segments(A, B, max_edge)
    verts = np.concatenate([extra, V])
    scale = float(np.ptp(verts, axis=0).max()) or 1.0
    key = np.round(verts / (1e-9 * scale)).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inv = inv.reshape(-1)
    segs = inv[len(extra) + S]
    return verts[first], segs[segs[:, 0] != segs[:, 1]], inv[: len(extra)]


def _triangle_map(
    nodes: NDArray[np.float64],
    tris: NDArray[np.int64],
    term_old: NDArray[np.int64],
    max_edge: float,
) -> TriangleMap:
    """The :class:`TriangleMap` of the kept triangles ``tris (k, 3)`` over ``nodes (m, 2)``:
    nodes no kept triangle uses are dropped and the rest renumbered; ``term_old`` are the
    terminals' node numbers before.

    Raises
    ------
    PlanningError
        When a terminal is in no kept triangle (not in free space).
    """
    used = np.zeros(len(nodes), dtype=bool)
    used[tris.reshape(-1)] = True
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
