"""Navigation meshes for Polyanya: convex polygons tiling free space, their neighbours across
each edge, and a point-location grid.

One structure serves every source (:class:`NavMesh`):

* Polyanya ``.mesh`` version 2 files (:meth:`NavMesh.read`), the format of the authors' code and
  of the Moving AI navigation-mesh benchmarks;
* triangulations weldplan builds itself (:meth:`NavMesh.from_triangles`, e.g. the
  :class:`~weldplan.planar.meshmap.TriangleMap` of a scenario);
* Moving AI grids (:func:`grid_navmesh`): the outline of the blocked cells triangulated by
  Triangle (cell ``(x, y)`` covers ``[x, x + 1] x [y, y + 1]``, the convention of Polyanya's
  grid-derived meshes, whose scenario runner takes the ``.scen`` values as raw points).

Polygons are stored counter-clockwise. Edge ``k`` of a polygon runs from its vertex ``k`` to
vertex ``k + 1``; seen from inside the polygon, vertex ``k`` is the edge's right end and
``k + 1`` its left end. ``neighbours[p][k]`` is the polygon across edge ``k`` (``-1``: obstacle)
and ``opposite[p][k]`` the index of the same edge in that neighbour. (A ``.mesh`` file lists
neighbour ``k`` across the edge from vertex ``k - 1`` to vertex ``k``; the reader shifts it.)
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError

log = logging.getLogger(__name__)

#: geometric tolerance relative to the mesh's bounding-box diagonal
REL_EPS = 1e-9


class NavMesh:
    """Convex polygons tiling free space (see the module docstring for the conventions).

    Parameters
    ----------
    vertices
        ``(nv, 2) float``: vertex coordinates (map units).
    polygons
        Vertex indices of each polygon, counter-clockwise (clockwise ones are reversed).
    neighbours
        Optional polygon across each edge in the class's convention (``-1`` for obstacle);
        found by matching shared edges when omitted.

    Attributes
    ----------
    corner
        ``(nv,) bool``: the vertices where Polyanya lets a path turn (non-observable
        successors): an obstacle beside them and more than 180 degrees of free space around
        them (:func:`_turning_vertices`).
    n_exits
        ``(np,) int``: traversable edges of each polygon (dead-end and intermediate pruning).
    """

    def __init__(
        self,
        vertices: ArrayLike,
        polygons: list[Any],
        neighbours: list[Any] | None = None,
    ) -> None:
        V = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
        sizes = np.array([len(p) for p in polygons], dtype=np.int64)
        ptr = np.zeros(len(sizes) + 1, dtype=np.int64)
        np.cumsum(sizes, out=ptr[1:])
        pv = _flat(polygons)
        nb = None if neighbours is None else _flat(neighbours)
        owner = np.repeat(np.arange(len(sizes)), sizes)
        local = np.arange(len(pv)) - ptr[owner]
        n = sizes[owner]
        nxt = ptr[owner] + (local + 1) % np.maximum(n, 1)
        cross = V[pv, 0] * V[pv[nxt], 1] - V[pv[nxt], 0] * V[pv, 1]
        cw = (np.bincount(owner, weights=cross, minlength=len(sizes)) < 0)[owner]
        if cw.any():  # clockwise polygons reversed: vertex i <- n-1-i, edge i <- n-2-i (mod n)
            base = ptr[owner]
            pv = np.where(cw, pv[base + n - 1 - local], pv)
            if nb is not None:
                nb = np.where(cw, nb[base + (n - 2 - local) % n], nb)
        j_opp = _match_flat(pv, pv[nxt], owner, ptr)
        if nb is None:
            nb = np.where(j_opp >= 0, owner[np.maximum(j_opp, 0)], -1)
        else:
            wrong = (nb >= 0) & ((j_opp < 0) | (owner[np.maximum(j_opp, 0)] != nb))
            if wrong.any():
                k = int(np.nonzero(wrong)[0][0])
                raise InputError(
                    f"polygon {owner[k]} edge {local[k]}: neighbour {nb[k]} does not share it"
                )
        opp = np.where(nb >= 0, j_opp - ptr[np.maximum(nb, 0)], -1)
        #: flat arrays: polygon p's vertices are pv[ptr[p]:ptr[p + 1]], likewise its
        #: neighbours pnb and the index of each edge in its neighbour popp
        self.ptr, self.pv, self.pnb, self.popp = ptr, pv, nb, opp
        self.vertices = V
        cut = ptr[1:-1]
        self.polygons = [x.tolist() for x in np.split(pv, cut)]
        self.neighbours = [x.tolist() for x in np.split(nb, cut)]
        self.opposite = [x.tolist() for x in np.split(opp, cut)]
        self.vx = V[:, 0].tolist()
        self.vy = V[:, 1].tolist()
        lo, hi = (V.min(axis=0), V.max(axis=0)) if len(V) else (np.zeros(2), np.ones(2))
        self.lo, self.hi = lo, hi
        self.scale = float(max(np.hypot(*(hi - lo)), 1e-300))
        self.eps = REL_EPS * self.scale
        self.corner = _turning_vertices(
            V, pv, pv[nxt], pv[ptr[owner] + (local - 1) % np.maximum(n, 1)], nb
        )
        self.n_exits = np.bincount(owner[nb >= 0], minlength=len(sizes))
        self._locator = _PolygonGrid(V, self.polygons)
        log.debug("navmesh: %d vertices, %d polygons", len(V), len(self.polygons))

    @property
    def n_polygons(self) -> int:
        return len(self.polygons)

    # ------------------------------------------------------------------------ construction
    @classmethod
    def read(cls, path: str | Path) -> NavMesh:
        """Read a Polyanya ``.mesh`` version 2 file.

        Raises
        ------
        InputError
            Naming the file and line of the first malformed or inconsistent record.
        """
        path = Path(path)
        try:
            text = path.read_text()
        except OSError as exc:
            raise InputError(f"cannot read: {exc.strerror}", path=path) from None
        lines = [(k, ln.split()) for k, ln in enumerate(text.splitlines(), 1) if ln.strip()]
        if len(lines) < 3 or lines[0][1] != ["mesh"] or lines[1][1] != ["2"]:
            raise InputError("not a Polyanya mesh version 2 ('mesh' then '2')", path=path, line=1)
        try:
            nv, npoly = (int(x) for x in lines[2][1])
        except ValueError:
            raise InputError(
                "expected 'V P' (vertex and polygon counts)", path=path, line=lines[2][0]
            ) from None
        if len(lines) < 3 + nv + npoly:
            raise InputError(
                f"expected {nv} vertex and {npoly} polygon lines, the file ends first",
                path=path,
                line=lines[-1][0],
            )
        verts = np.empty((nv, 2))
        for v in range(nv):
            k, f = lines[3 + v]
            try:
                verts[v] = float(f[0]), float(f[1])
                n = int(f[2])
                if len(f) != 3 + n:
                    raise ValueError
            except (ValueError, IndexError):
                raise InputError(
                    "expected a vertex 'x y n p1 .. pn'", path=path, line=k, field="vertex"
                ) from None
        polys, neigh = [], []
        for q in range(npoly):
            k, f = lines[3 + nv + q]
            try:
                n = int(f[0])
                ids = [int(x) for x in f[1:]]
                if n < 3 or len(ids) != 2 * n:
                    raise ValueError
            except ValueError:
                raise InputError(
                    "expected a polygon 'n v1 .. vn p1 .. pn' with n >= 3",
                    path=path,
                    line=k,
                    field="polygon",
                ) from None
            vs, nb = ids[:n], ids[n:]
            if min(vs) < 0 or max(vs) >= nv or max(nb) >= npoly or min(nb) < -1:
                raise InputError(
                    "vertex or neighbour index out of range", path=path, line=k, field="polygon"
                )
            polys.append(vs)
            neigh.append(nb[1:] + nb[:1])  # file: neighbour k across edge (k - 1, k)
        try:
            return cls(verts, polys, neigh)
        except InputError as exc:
            raise InputError(str(exc), path=path) from None

    @classmethod
    def from_triangles(cls, nodes: ArrayLike, cells: ArrayLike) -> NavMesh:
        """A mesh of triangles ``cells (k, 3)`` over ``nodes (m, 2)`` (e.g. a
        :class:`~weldplan.planar.meshmap.TriangleMap`); neighbours by shared edges."""
        return cls(nodes, list(np.asarray(cells, dtype=np.int64).reshape(-1, 3)))

    # ------------------------------------------------------------------------ point location
    def locate(self, point: ArrayLike) -> list[int]:
        """Polygons containing ``point (2,)`` (boundary within :attr:`eps` included): one for
        an interior point, two on a shared edge, all around a vertex, none outside."""
        x, y = (float(v) for v in np.asarray(point, dtype=np.float64).reshape(2))
        out = []
        vx, vy, eps = self.vx, self.vy, self.eps
        for p in self._locator.candidates(x, y):
            vs = self.polygons[p]
            n = len(vs)
            for k in range(n):
                a, b = vs[k], vs[(k + 1) % n]
                ex, ey = vx[b] - vx[a], vy[b] - vy[a]
                c = ex * (y - vy[a]) - ey * (x - vx[a])
                if c < -eps * math.hypot(ex, ey):
                    break
            else:
                out.append(p)
        return out


class _PolygonGrid:
    """A uniform bucket grid over polygon bounding boxes (about one polygon per cell), as CSR
    arrays: a point's candidate polygons are the ones registered in its cell."""

    def __init__(self, V: NDArray[np.float64], polygons: list[list[int]]) -> None:
        n = len(polygons)
        if n == 0:
            self.lo, self.h, self.nx, self.ny = np.zeros(2), 1.0, 1, 1
            self.ptr, self.idx = [0, 0], []
            return
        sizes = np.array([len(p) for p in polygons])
        flat = np.concatenate([np.asarray(p) for p in polygons])
        owner = np.repeat(np.arange(n), sizes)
        plo = np.full((n, 2), np.inf)
        phi = np.full((n, 2), -np.inf)
        np.minimum.at(plo, owner, V[flat])
        np.maximum.at(phi, owner, V[flat])
        lo, hi = plo.min(axis=0), phi.max(axis=0)
        span = np.maximum(hi - lo, 1e-12)
        self.h = float(max(span.max() / 4096.0, math.sqrt(span[0] * span[1] / n)))
        pad = 1e-9 * float(np.hypot(*span))
        self.lo = lo - pad
        self.nx = int(span[0] / self.h) + 2
        self.ny = int(span[1] / self.h) + 2
        i0 = np.floor((plo - pad - self.lo) / self.h).astype(np.int64)
        i1 = np.floor((phi + pad - self.lo) / self.h).astype(np.int64)
        cx = i1[:, 0] - i0[:, 0] + 1
        cy = i1[:, 1] - i0[:, 1] + 1
        cnt = cx * cy
        poly = np.repeat(np.arange(n), cnt)
        k = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        cell = (i0[poly, 0] + k // cy[poly]) * self.ny + i0[poly, 1] + k % cy[poly]
        order = np.argsort(cell, kind="stable")
        ptr = np.zeros(self.nx * self.ny + 1, dtype=np.int64)
        np.cumsum(np.bincount(cell, minlength=self.nx * self.ny), out=ptr[1:])
        self.ptr = ptr.tolist()
        self.idx = poly[order].tolist()

    def candidates(self, x: float, y: float) -> list[int]:
        i = int(math.floor((x - self.lo[0]) / self.h))
        j = int(math.floor((y - self.lo[1]) / self.h))
        if not (0 <= i < self.nx and 0 <= j < self.ny):
            return []
        c = i * self.ny + j
        return self.idx[self.ptr[c] : self.ptr[c + 1]]


def _turning_vertices(
    V: NDArray[np.float64],
    a: NDArray[np.int64],
    nxt: NDArray[np.int64],
    prev: NDArray[np.int64],
    nb: NDArray[np.int64],
) -> NDArray[np.bool_]:
    """Vertices where a taut path may turn: on the boundary (an obstacle beside them) with a
    free angle (the polygons' interior angles there, summed) above 180 degrees, or beside two or
    more obstacle wedges (where obstacles touch; kept, since each wedge's own angle is not
    measured here). A shortest path turns only around reflex obstacle corners, so dropping the
    others removes successors that cannot lie on an optimal path (the paper turns at every
    vertex beside an obstacle). ``a, nxt, prev`` are each polygon corner's vertex and its
    polygon's next and previous vertices (flat), ``nb`` the neighbour across edge
    ``a -> nxt``."""
    nv = len(V)
    u = V[prev] - V[a]
    w = V[nxt] - V[a]
    ang = np.arctan2(w[:, 0] * u[:, 1] - w[:, 1] * u[:, 0], np.sum(u * w, axis=1))
    ang = np.where(ang < 0, ang + 2 * np.pi, ang)  # interior angle of a ccw polygon, in (0, 2 pi)
    free = np.bincount(a, weights=ang, minlength=nv)
    bnd = nb < 0
    walls = np.bincount(a[bnd], minlength=nv) + np.bincount(nxt[bnd], minlength=nv)
    return (walls >= 4) | ((walls == 2) & (free > np.pi + 1e-9))


def _flat(rows: list[Any]) -> NDArray[np.int64]:
    """Concatenated integer rows."""
    if not len(rows):
        return np.zeros(0, dtype=np.int64)
    return np.concatenate([np.asarray(r, dtype=np.int64).reshape(-1) for r in rows])


def _match_flat(
    a: NDArray[np.int64], b: NDArray[np.int64], owner: NDArray[np.int64], ptr: NDArray[np.int64]
) -> NDArray[np.int64]:
    """For each directed edge ``a[k] -> b[k]``, the flat index of the reversed edge
    ``b -> a`` (``-1`` if no polygon has it)."""
    if not len(a):
        return np.zeros(0, dtype=np.int64)
    m = int(max(a.max(), b.max())) + 1
    key = a * m + b
    rev = b * m + a
    order = np.argsort(key, kind="stable")
    ks = key[order]
    pos = np.minimum(np.searchsorted(ks, rev), len(ks) - 1)
    return np.where(ks[pos] == rev, order[pos], -1)


def grid_navmesh(free: ArrayLike) -> NavMesh:
    """The navigation mesh of a grid ``free (nx, ny) bool`` (indexed ``[x, y]``): cell
    ``(x, y)`` covers ``[x, x + 1] x [y, y + 1]``; the outline of the blocked cells and the
    grid's frame are triangulated by Triangle (a constrained Delaunay triangulation, no quality
    refinement), and the triangles of free cells kept. Blocked cells that touch only at a
    corner leave a vertex no path crosses (the triangles on either side share no edge)."""
    from weldplan.planar.meshmap import grid_boundary_segments, triangulate_segments

    F = np.asarray(free, dtype=bool)
    nx, ny = F.shape
    occ = np.ones((nx + 2, ny + 2), dtype=bool)  # a blocked ring gives the frame as outline
    occ[1:-1, 1:-1] = ~F
    A, B = grid_boundary_segments(occ, origin=(-1.0, -1.0))

    def keep(c: NDArray[np.float64]) -> NDArray[np.bool_]:
        ij = np.floor(c).astype(np.int64)
        ok = (ij[:, 0] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] >= 0) & (ij[:, 1] < ny)
        ok[ok] = F[ij[ok, 0], ij[ok, 1]]
        return ok

    tmap = triangulate_segments(A, B, keep, max_edge=math.inf, min_angle=0.0)
    return NavMesh.from_triangles(tmap.nodes, tmap.cells)
