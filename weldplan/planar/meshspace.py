"""The free space of a Polyanya navigation mesh (``.mesh`` v2) with the same segment queries as
:class:`~weldplan.geometry.obstacles2d.Obstacles2D`, so the visibility graph runs on either.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError
from weldplan.geometry.obstacles2d import point_segment_distance

log = logging.getLogger(__name__)


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
