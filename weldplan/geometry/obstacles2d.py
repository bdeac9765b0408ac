"""Planar obstacles and the vectorised queries every 2D planner needs.

One :class:`Obstacles2D` holds a map's obstacles in three array families, each queried without
Python loops over points or segments:

* circles: centres ``(C, 2)`` and radii ``(C,)``;
* axis-aligned rectangles ``(R, 4)`` as ``(xmin, ymin, xmax, ymax)`` (occupancy grids become
  rectangles through :func:`grid_to_rectangles`, one rectangle per run of occupied cells in a row);
* general simple polygons (convex or concave), a list of ``(k, 2)`` vertex arrays.

Queries take points ``(..., 2)`` or segments ``A, B (..., 2)`` of any leading shape, so one call
tests ``P paths x S segments`` against all ``O`` obstacles at once:

* :meth:`Obstacles2D.signed_distance`: per-obstacle signed distance ``(..., O)`` (negative inside);
* :meth:`Obstacles2D.clearance`: distance to the nearest obstacle (negative = penetration);
* :meth:`Obstacles2D.inside_length`: length of each segment inside obstacles (summed over
  obstacles, so a stretch inside two overlapping obstacles counts twice);
* :meth:`Obstacles2D.segments_hit`: whether a segment enters the interior of an obstacle (grazing
  a boundary or a vertex is not a collision: any-angle shortest paths touch vertices), or passes
  through a pinch point, a point where two obstacles touch (a path may not squeeze through).

Units are whatever the scenario uses (the papers' maps are unitless grid units).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.primitives2d import (  # noqa: F401 - re-exported
    cross2,
    even_odd,
    grid_to_rectangles,
    point_segment_distance,
    polygon_area,
    polygon_is_simple,
    segments_touch,
)

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

#: segments inside obstacles for less than this length (relative to the map size) are free:
#: it absorbs floating-point noise where a path grazes a boundary.
GRAZE_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class Obstacles2D:
    """The obstacles of a planar map (see the module docstring).

    Parameters
    ----------
    circles
        ``(C, 3) float``: ``x, y, radius``.
    rectangles
        ``(R, 4) float``: ``xmin, ymin, xmax, ymax``.
    polygons
        Simple polygons, each ``(k, 2) float`` (either orientation; not closed explicitly).
    """

    circles: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    rectangles: FloatArray = field(default_factory=lambda: np.zeros((0, 4)))
    polygons: tuple[FloatArray, ...] = ()

    def __post_init__(self) -> None:
        c = np.asarray(self.circles, dtype=np.float64).reshape(-1, 3)
        r = np.asarray(self.rectangles, dtype=np.float64).reshape(-1, 4)
        polys = tuple(np.asarray(p, dtype=np.float64).reshape(-1, 2) for p in self.polygons)
        if np.any(c[:, 2] <= 0):
            raise ValueError("circle radii must be positive")
        if np.any(r[:, 2] <= r[:, 0]) or np.any(r[:, 3] <= r[:, 1]):
            raise ValueError("rectangles need xmin < xmax and ymin < ymax")
        for arr in (c, r, *polys):
            arr.setflags(write=False)
        object.__setattr__(self, "circles", c)
        object.__setattr__(self, "rectangles", r)
        object.__setattr__(self, "polygons", polys)
        # all polygon edges stacked, with the polygon each belongs to
        if polys:
            a = np.concatenate(polys)
            b = np.concatenate([np.roll(p, -1, axis=0) for p in polys])
            owner = np.concatenate([np.full(len(p), i) for i, p in enumerate(polys)])
            offsets = np.cumsum([0] + [len(p) for p in polys])[:-1]
        else:
            a = b = np.zeros((0, 2))
            owner = np.zeros(0, dtype=np.int64)
            offsets = np.zeros(0, dtype=np.int64)
        object.__setattr__(self, "_edge_a", a)
        object.__setattr__(self, "_edge_b", b)
        object.__setattr__(self, "_edge_owner", owner)
        object.__setattr__(self, "_edge_offsets", offsets)
        object.__setattr__(self, "_pinch", None)

    # ------------------------------------------------------------------ basics
    @property
    def n_obstacles(self) -> int:
        return len(self.circles) + len(self.rectangles) + len(self.polygons)

    @property
    def scale(self) -> float:
        """A length typical of the map (the diagonal of the obstacles' bounding box, or 1)."""
        lo, hi = self.bounding_box()
        d = float(np.hypot(*(hi - lo)))
        return d if d > 0 else 1.0

    def bounding_box(self) -> tuple[FloatArray, FloatArray]:
        """``(lo (2,), hi (2,))`` of all obstacles (zeros when there are none)."""
        los, his = [], []
        if len(self.circles):
            los.append(self.circles[:, :2] - self.circles[:, 2:3])
            his.append(self.circles[:, :2] + self.circles[:, 2:3])
        if len(self.rectangles):
            los.append(self.rectangles[:, :2])
            his.append(self.rectangles[:, 2:])
        if self.polygons:
            los.append(self._edge_a)
            his.append(self._edge_a)
        if not los:
            return np.zeros(2), np.zeros(2)
        return np.min(np.concatenate(los), axis=0), np.max(np.concatenate(his), axis=0)

    def as_polygons(self, circle_sides: int = 64, circumscribed: bool = True) -> Obstacles2D:
        """The same map with circles replaced by regular polygons.

        ``circumscribed=True`` gives polygons that contain their circle (shortest paths around
        them are upper bounds of the true ones); ``False`` inscribed polygons (lower bounds).
        A circle of radius r becomes a polygon within ``r (1/cos(pi/n) - 1)`` of it.
        """
        if not len(self.circles):
            return self
        n = int(circle_sides)
        ang = (np.arange(n) + 0.5) * 2 * np.pi / n
        rad = 1.0 / np.cos(np.pi / n) if circumscribed else 1.0
        unit = np.stack([np.cos(ang), np.sin(ang)], axis=1) * rad
        polys = [c[:2] + c[2] * unit for c in self.circles]
        return Obstacles2D(rectangles=self.rectangles, polygons=(*self.polygons, *polys))

    # ------------------------------------------------------------------ points
    def signed_distance(self, points: ArrayLike) -> FloatArray:
        """Signed distance from points ``(..., 2)`` to each obstacle: ``(..., O)``.

        Obstacles are ordered circles, rectangles, polygons. Negative inside.
        """
        P = np.asarray(points, dtype=np.float64)
        lead = P.shape[:-1]
        parts = []
        if len(self.circles):
            c = self.circles
            parts.append(np.linalg.norm(P[..., None, :] - c[:, :2], axis=-1) - c[:, 2])
        if len(self.rectangles):
            r = self.rectangles
            ctr = 0.5 * (r[:, :2] + r[:, 2:])
            half = 0.5 * (r[:, 2:] - r[:, :2])
            q = np.abs(P[..., None, :] - ctr) - half
            outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
            inside = np.minimum(np.max(q, axis=-1), 0.0)
            parts.append(outside + inside)
        if self.polygons:
            parts.append(self._polygon_signed_distance(P))
        if not parts:
            return np.zeros((*lead, 0))
        return np.concatenate(parts, axis=-1)

    def _polygon_signed_distance(self, P: FloatArray) -> FloatArray:
        a, b = self._edge_a, self._edge_b
        dist = point_segment_distance(P[..., None, :], a, b)  # (..., E)
        dmin = np.minimum.reduceat(dist, self._edge_offsets, axis=-1)
        return np.where(self._polygon_contains(P), -dmin, dmin)

    def _polygon_contains(self, P: FloatArray) -> NDArray[np.bool_]:
        """Even-odd point-in-polygon of points ``(..., 2)`` for each polygon: ``(..., n_poly)``."""
        a, b = self._edge_a, self._edge_b
        px = P[..., None, 0]
        py = P[..., None, 1]
        cond = (a[:, 1] > py) != (b[:, 1] > py)
        dy = b[:, 1] - a[:, 1]
        xint = a[:, 0] + (py - a[:, 1]) * (b[:, 0] - a[:, 0]) / np.where(dy == 0, 1.0, dy)
        cross = cond & (px < xint)
        counts = np.add.reduceat(cross.astype(np.int32), self._edge_offsets, axis=-1)
        return (counts % 2) == 1

    def clearance(self, points: ArrayLike) -> FloatArray:
        """Distance from points ``(..., 2)`` to the nearest obstacle (negative inside): ``(...)``.

        ``+inf`` when the map has no obstacles.
        """
        sd = self.signed_distance(points)
        if sd.shape[-1] == 0:
            return np.full(sd.shape[:-1], np.inf)
        return np.min(sd, axis=-1)

    def contains(self, points: ArrayLike, tol: float = 0.0) -> NDArray[np.bool_]:
        """Whether points ``(..., 2)`` lie strictly inside an obstacle (deeper than ``tol``)."""
        return self.clearance(points) < -tol

    def penetration(self, points: ArrayLike) -> FloatArray:
        """Penetration depth ``max(0, -signed distance)`` into each obstacle: ``(..., O)``."""
        return np.maximum(-self.signed_distance(points), 0.0)

    def total_penetration(self, points: ArrayLike) -> FloatArray:
        """Sum over obstacles of the penetration depth of points ``(..., 2)``: ``(...)``.

        The fast path of ``penetration(points).sum(-1)`` for population fitness.
        """
        P = np.asarray(points, dtype=np.float64)
        total = np.zeros(P.shape[:-1])
        x = P[..., 0, None]
        y = P[..., 1, None]
        if len(self.circles):
            c = self.circles
            # squared distances by one matrix product; square roots only where inside
            d2 = (P @ (-2.0 * c[:, :2].T)) + np.sum(P * P, axis=-1)[..., None]
            d2 += np.sum(c[:, :2] ** 2, axis=1)
            inside = d2 < c[:, 2] ** 2
            if np.any(inside):
                depth = np.zeros_like(d2)
                rr = np.broadcast_to(c[:, 2], d2.shape)
                depth[inside] = rr[inside] - np.sqrt(np.maximum(d2[inside], 0.0))
                total += np.sum(depth, axis=-1)
        if len(self.rectangles):
            r = self.rectangles
            # inside a rectangle the depth is the distance to its nearest side
            depth = np.minimum(
                np.minimum(x - r[:, 0], r[:, 2] - x), np.minimum(y - r[:, 1], r[:, 3] - y)
            )
            total += np.sum(np.maximum(depth, 0.0), axis=-1)
        if self.polygons:
            total += np.sum(np.maximum(-self._polygon_signed_distance(P), 0.0), axis=-1)
        return total

    # ---------------------------------------------------------------- segments
    def inside_length(
        self, A: ArrayLike, B: ArrayLike, *, per_obstacle: bool = False, closed: bool = False
    ) -> FloatArray:
        """Length of segments ``A -> B (..., 2)`` inside obstacles.

        Returns ``(...)`` summed over obstacles, or ``(..., O)`` with ``per_obstacle``.
        ``closed=True`` counts stretches along a polygon's boundary as inside (for polygons that
        tile free space, such as navigation meshes); otherwise only the interior counts.
        Circles by the chord formula, rectangles by Liang-Barsky clipping, polygons by splitting
        each segment at its crossings with the polygon's edges and testing the pieces' midpoints.
        """
        A = np.asarray(A, dtype=np.float64)
        B = np.asarray(B, dtype=np.float64)
        A, B = np.broadcast_arrays(A, B)
        seglen = np.linalg.norm(B - A, axis=-1)
        parts = []
        if len(self.circles):
            parts.append(self._circle_fraction(A, B) * seglen[..., None])
        if len(self.rectangles):
            if per_obstacle:
                parts.append(self._rect_fraction(A, B) * seglen[..., None])
            else:  # sparse: only the rectangles each segment's bounding box overlaps
                parts.append((self._rect_fraction_sum(A, B) * seglen)[..., None])
        if self.polygons:
            parts.append(self._polygon_fraction(A, B, closed) * seglen[..., None])
        out = np.concatenate(parts, axis=-1) if parts else np.zeros((*A.shape[:-1], 0))
        return out if per_obstacle else np.sum(out, axis=-1)

    def _circle_fraction(self, A: FloatArray, B: FloatArray) -> FloatArray:
        c = self.circles
        d = (B - A)[..., None, :]
        f = A[..., None, :] - c[:, :2]
        aa = np.sum(d * d, axis=-1)
        bb = 2 * np.sum(f * d, axis=-1)
        cc = np.sum(f * f, axis=-1) - c[:, 2] ** 2
        disc = bb * bb - 4 * aa * cc
        ok = (disc > 0) & (aa > 0)
        sq = np.sqrt(np.where(ok, disc, 0.0))
        den = np.where(aa > 0, 2 * aa, 1.0)
        t0 = np.clip((-bb - sq) / den, 0.0, 1.0)
        t1 = np.clip((-bb + sq) / den, 0.0, 1.0)
        return np.where(ok, np.maximum(t1 - t0, 0.0), 0.0)

    def _rect_interval(self, A: FloatArray, B: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Parameter interval ``[t0, t1]`` of segments ``(..., 2)`` strictly inside each
        rectangle by Liang-Barsky clipping: two ``(..., R)`` arrays (``t1 <= t0`` when empty)."""
        r = self.rectangles
        return self._slab_interval(A[..., None, :], B[..., None, :], r[:, :2], r[:, 2:])

    def _rect_pairs(
        self, A: FloatArray, B: FloatArray, pad: float = 0.0
    ) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """``(segment, rectangle)`` pairs of segments ``(S, 2)`` whose bounding box (padded by
        ``pad``) overlaps the rectangle: the only pairs that can share a point."""
        r = self.rectangles
        lo, hi = np.minimum(A, B) - pad, np.maximum(A, B) + pad
        out_s, out_r = [], []
        chunk = max(1, 4_000_000 // max(len(r), 1))
        for s in range(0, len(A), chunk):
            m = (
                (lo[s : s + chunk, None, 0] <= r[:, 2])
                & (hi[s : s + chunk, None, 0] >= r[:, 0])
                & (lo[s : s + chunk, None, 1] <= r[:, 3])
                & (hi[s : s + chunk, None, 1] >= r[:, 1])
            )
            si, ri = np.nonzero(m)
            out_s.append(si + s)
            out_r.append(ri)
        if not out_s:
            return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
        return np.concatenate(out_s), np.concatenate(out_r)

    @staticmethod
    def _slab_interval(
        A: FloatArray, B: FloatArray, lo: FloatArray, hi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Liang-Barsky clipping of segments ``(P, 2)`` against boxes ``lo, hi (P, 2)`` (or any
        shapes that broadcast): the parameter interval ``[t0, t1]`` strictly inside (``t1 <= t0``
        when empty)."""
        d = B - A
        with np.errstate(divide="ignore", invalid="ignore"):
            t_lo = (lo - A) / d
            t_hi = (hi - A) / d
        tmin = np.minimum(t_lo, t_hi)
        tmax = np.maximum(t_lo, t_hi)
        # a zero direction component: inside the slab for all t (strictly), or never
        par = d == 0
        inslab = (A > lo) & (A < hi)
        tmin = np.where(par, np.where(inslab, -np.inf, np.inf), tmin)
        tmax = np.where(par, np.where(inslab, np.inf, -np.inf), tmax)
        return np.maximum(tmin.max(axis=-1), 0.0), np.minimum(tmax.min(axis=-1), 1.0)

    def _rect_fraction_sum(self, A: FloatArray, B: FloatArray) -> FloatArray:
        """Fraction of segments ``(..., 2)`` inside rectangles, summed: ``(...)``; clipped only
        against the rectangles their bounding boxes overlap."""
        lead = A.shape[:-1]
        A2, B2 = A.reshape(-1, 2), B.reshape(-1, 2)
        si, ri = self._rect_pairs(A2, B2)
        r = self.rectangles[ri]
        t0, t1 = self._slab_interval(A2[si], B2[si], r[:, :2], r[:, 2:])
        out = np.bincount(si, weights=np.maximum(t1 - t0, 0.0), minlength=len(A2))
        return out.reshape(lead)

    def _rect_fraction(self, A: FloatArray, B: FloatArray) -> FloatArray:
        lead = A.shape[:-1]
        A2, B2 = A.reshape(-1, 2), B.reshape(-1, 2)
        R = len(self.rectangles)
        out = np.empty((len(A2), R))
        chunk = max(1, 1_000_000 // R)  # (segments, rectangles, 2) temporaries per chunk
        for s in range(0, len(A2), chunk):
            t0, t1 = self._rect_interval(A2[s : s + chunk], B2[s : s + chunk])
            out[s : s + chunk] = np.maximum(t1 - t0, 0.0)
        return out.reshape(*lead, R)

    def _polygon_fraction(self, A: FloatArray, B: FloatArray, closed: bool = False) -> FloatArray:
        lead = A.shape[:-1]
        A2 = A.reshape(-1, 2)
        B2 = B.reshape(-1, 2)
        out = np.zeros((A2.shape[0], len(self.polygons)))
        for k, poly in enumerate(self.polygons):
            pa = poly
            pb = np.roll(poly, -1, axis=0)
            d = B2 - A2  # (S, 2)
            e = pb - pa  # (K, 2)
            den = cross2(d[:, None, :], e[None, :, :])  # (S, K)
            w = pa[None, :, :] - A2[:, None, :]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = cross2(w, e[None]) / den
                u = cross2(w, d[:, None, :]) / den
            valid = (den != 0) & (u >= 0) & (u <= 1) & (t > 0) & (t < 1)
            ts = np.where(valid, t, 1.0)
            ts = np.sort(np.concatenate([np.zeros((len(A2), 1)), ts, np.ones((len(A2), 1))], 1), 1)
            mids = 0.5 * (ts[:, 1:] + ts[:, :-1])  # (S, K+1)
            lens = ts[:, 1:] - ts[:, :-1]
            M = A2[:, None, :] + mids[..., None] * d[:, None, :]
            # even-odd test of the pieces' midpoints; the distance to the boundary is needed
            # only for the pieces it calls inside (open) or outside (closed), to sort out
            # pieces that run along an edge
            par = even_odd(M, pa, pb)
            tol = GRAZE_TOL * np.maximum(np.linalg.norm(d, axis=1), 1.0)[:, None]
            check = (par if not closed else ~par) & (lens > 0)
            on_edge = np.zeros_like(par)
            if np.any(check):
                dist = point_segment_distance(M[check][:, None, :], pa, pb).min(axis=1)
                on_edge[check] = dist <= np.broadcast_to(tol, par.shape)[check]
            inside = (par | on_edge) if closed else (par & ~on_edge)
            out[:, k] = np.sum(np.where(inside & (lens > 0), lens, 0.0), axis=1)
        return out.reshape(*lead, len(self.polygons))

    def pinch_points(self) -> FloatArray:
        """Points ``(n, 2)`` where obstacles touch so that free space is pinched to a point.

        A vertex is a pinch point when the free directions around it form two or more separate
        fans (sampled at 64 directions just off the vertex). Cached.
        """
        if self._pinch is not None:
            return self._pinch
        verts = self.vertices()
        if len(verts) == 0:
            pinch = np.zeros((0, 2))
        else:
            runs, _ = self._free_fans(verts)
            pinch = verts[runs >= 2]
        pinch.setflags(write=False)
        object.__setattr__(self, "_pinch", pinch)
        return pinch

    def vertices(self) -> FloatArray:
        """Distinct vertices ``(n, 2)`` of rectangles and polygons (circles have none)."""
        parts = [np.zeros((0, 2))]
        if len(self.rectangles):
            r = self.rectangles
            parts.append(r[:, [0, 1]])
            parts.append(r[:, [2, 1]])
            parts.append(r[:, [2, 3]])
            parts.append(r[:, [0, 3]])
        if self.polygons:
            parts.append(self._edge_a)
        return np.unique(np.concatenate(parts), axis=0)

    def _free_fans(self, verts: FloatArray, n_dir: int = 64) -> tuple[NDArray, NDArray]:
        """Number of separate free fans and the free fraction around each vertex ``(n, 2)``.

        Rectangles are tested only against the vertices inside their bounding box (padded by
        the ring radius): testing every ring point against every rectangle made this
        ``vertices x rectangles x n_dir`` (about 10 minutes on the 3,838 touching grid
        rectangles of rtb-data's house floorplan; now a second).
        """
        eps = 1e-7 * self.scale
        ang = (np.arange(n_dir) + 0.5) * 2 * np.pi / n_dir + 1e-3
        ring = verts[:, None, :] + eps * np.stack([np.cos(ang), np.sin(ang)], axis=1)
        occ = np.zeros(ring.shape[:2], dtype=bool)
        r = self.rectangles
        if len(r):
            chunk = max(1, 2_000_000 // len(r))
            for s in range(0, len(verts), chunk):
                v = verts[s : s + chunk]
                near = (
                    (v[:, None, 0] >= r[:, 0] - 2 * eps)
                    & (v[:, None, 0] <= r[:, 2] + 2 * eps)
                    & (v[:, None, 1] >= r[:, 1] - 2 * eps)
                    & (v[:, None, 1] <= r[:, 3] + 2 * eps)
                )
                vi, ri = np.nonzero(near)
                Q = ring[s + vi]  # (p, n_dir, 2)
                R = r[ri][:, None, :]
                inside = (
                    (Q[..., 0] > R[..., 0])
                    & (Q[..., 0] < R[..., 2])
                    & (Q[..., 1] > R[..., 1])
                    & (Q[..., 1] < R[..., 3])
                )
                np.logical_or.at(occ, s + vi, inside)
        if len(self.circles) or self.polygons:
            rest = Obstacles2D(circles=self.circles, polygons=self.polygons)
            chunk = max(1, 200_000 // (n_dir * max(rest.n_obstacles, 1)))
            for s in range(0, len(verts), chunk):
                occ[s : s + chunk] |= rest.contains(ring[s : s + chunk])
        free = ~occ
        starts = free & ~np.roll(free, 1, axis=1)
        runs = np.sum(starts, axis=1)
        runs = np.where(np.all(free, axis=1), 1, runs)
        return runs, np.mean(free, axis=1)

    def segments_hit(self, A: ArrayLike, B: ArrayLike) -> NDArray[np.bool_]:
        """Whether segments ``A -> B (..., 2)`` collide: ``(...) bool``.

        A segment collides when more than ``GRAZE_TOL x map scale`` of it lies inside obstacles,
        or when a pinch point (:meth:`pinch_points`) lies in its relative interior.
        """
        return self.segments_hit_length(A, B)[0]

    def segments_hit_length(self, A: ArrayLike, B: ArrayLike) -> tuple[NDArray, FloatArray]:
        """:meth:`segments_hit` and :meth:`inside_length` in one pass: ``((...), (...))``."""
        A = np.asarray(A, dtype=np.float64)
        B = np.asarray(B, dtype=np.float64)
        A, B = np.broadcast_arrays(A, B)
        tol = GRAZE_TOL * self.scale
        inside = self.inside_length(A, B)
        hit = inside > tol
        hit = hit | self._along_shared_boundary(A, B, hit, tol)
        pinch = self.pinch_points()
        if len(pinch):
            hit = hit | self._through_points(A, B, pinch, tol)
        return hit, inside

    def _along_shared_boundary(
        self, A: FloatArray, B: FloatArray, hit: NDArray[np.bool_], tol: float
    ) -> NDArray[np.bool_]:
        """Axis-parallel segments that run along a boundary shared by two rectangles.

        Two rectangles that share an edge (the row runs of an occupancy grid) block the line
        between them although neither interior contains it. For each segment parallel to an
        axis, the copies shifted just off both of its sides are clipped against every
        rectangle; a stretch inside rectangles on both sides is blocked. (Polygons sharing
        edges are not detected; the shipped maps have none.)
        """
        out = np.zeros(A.shape[:-1], dtype=bool)
        if not len(self.rectangles):
            return out
        d = B - A
        L = np.linalg.norm(d, axis=-1)
        flat = (np.abs(d[..., 1]) <= 1e-12 * L) | (np.abs(d[..., 0]) <= 1e-12 * L)
        idx = np.nonzero((flat & (L > tol) & ~hit).reshape(-1))[0]
        if not len(idx):
            return out
        A2, B2 = A.reshape(-1, 2)[idx], B.reshape(-1, 2)[idx]
        L2 = L.reshape(-1)[idx]
        nrm = np.stack([-(B2 - A2)[:, 1], (B2 - A2)[:, 0]], 1) / L2[:, None]
        delta = 1e-7 * self.scale
        both = np.zeros(len(idx), dtype=bool)
        # overlaps of the stretches inside rectangles on either side, summed over the pairs of
        # non-empty stretches only (all pairs made this rectangles^2 per segment: the house
        # floorplan's 3,838 rectangles stalled it)
        r = self.rectangles
        sides = []
        for sgn in (1.0, -1.0):
            Au, Bu = A2 + sgn * delta * nrm, B2 + sgn * delta * nrm
            si, ri = self._rect_pairs(Au, Bu)
            t0, t1 = self._slab_interval(Au[si], Bu[si], r[ri, :2], r[ri, 2:])
            keep = t1 > t0
            sides.append((si[keep], t0[keep], t1[keep]))  # sorted by segment
        (us, u0, u1), (ds, d0, d1) = sides
        lo_i = np.searchsorted(ds, us, side="left")
        cnt = np.searchsorted(ds, us, side="right") - lo_i
        pu = np.repeat(np.arange(len(us)), cnt)
        pd = np.repeat(lo_i, cnt) + (
            np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        )
        lo = np.maximum(u0[pu], d0[pd])
        hi = np.minimum(u1[pu], d1[pd])
        overlap = np.bincount(us[pu], weights=np.maximum(hi - lo, 0.0), minlength=len(idx))
        both[:] = overlap * L2 > tol
        flat_out = out.reshape(-1)
        flat_out[idx] = both
        return flat_out.reshape(out.shape)

    @staticmethod
    def _through_points(A: FloatArray, B: FloatArray, pts: FloatArray, tol: float) -> NDArray:
        d = point_segment_distance(pts, A[..., None, :], B[..., None, :])  # (..., n)
        at_end = (np.linalg.norm(pts - A[..., None, :], axis=-1) <= tol) | (
            np.linalg.norm(pts - B[..., None, :], axis=-1) <= tol
        )
        return np.any((d <= tol) & ~at_end, axis=-1)

    def segments_free(self, A: ArrayLike, B: ArrayLike) -> NDArray[np.bool_]:
        """``~segments_hit(A, B)``."""
        return ~self.segments_hit(A, B)

    def path_hits(self, paths: ArrayLike) -> NDArray[np.int64]:
        """Number of colliding segments of polylines ``(..., n, 2)``: ``(...) int``."""
        P = np.asarray(paths, dtype=np.float64)
        return np.sum(self.segments_hit(P[..., :-1, :], P[..., 1:, :]), axis=-1)
