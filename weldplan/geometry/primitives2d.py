"""Planar geometry primitives on arrays: occupancy grids as rectangles, simple-polygon tests,
polygon area, segment touching, even-odd point-in-polygon and point-to-segment distance.

The free functions :class:`~weldplan.geometry.obstacles2d.Obstacles2D` is built on (and that
module re-exports); all broadcast over leading axes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def grid_to_rectangles(
    occupied: ArrayLike, origin: Sequence[float] = (0.0, 0.0), cell: float = 1.0
) -> FloatArray:
    """Rectangles covering the occupied cells of a 2D occupancy grid.

    Parameters
    ----------
    occupied
        ``(nx, ny) bool``; ``occupied[i, j]`` is the cell ``[x0 + i*cell, x0 + (i+1)*cell] x
        [y0 + j*cell, y0 + (j+1)*cell]``.
    origin
        ``(x0, y0)``, the lower-left corner of cell ``(0, 0)``.
    cell
        Cell side length.

    Returns
    -------
    ``(R, 4) float``: one rectangle per maximal run of occupied cells along x in each row y.
    """
    occ = np.asarray(occupied, dtype=bool)
    if occ.ndim != 2:
        raise ValueError(f"occupancy grid must be 2D, got shape {occ.shape}")
    nx, ny = occ.shape
    pad = np.zeros((nx + 2, ny), dtype=np.int8)
    pad[1:-1] = occ
    d = np.diff(pad, axis=0)  # (nx + 1, ny): +1 at run start, -1 after run end
    rows, starts_i = np.nonzero(d.T == 1)  # sorted by row j, then by i
    _, ends_i = np.nonzero(d.T == -1)
    x0, y0 = float(origin[0]), float(origin[1])
    rect = np.empty((rows.size, 4))
    rect[:, 0] = x0 + starts_i * cell
    rect[:, 1] = y0 + rows * cell
    rect[:, 2] = x0 + ends_i * cell
    rect[:, 3] = y0 + (rows + 1) * cell
    return rect


def polygon_is_simple(vertices: ArrayLike) -> bool:
    """Whether a closed polygon ``(k, 2)`` has no self-intersections (and k >= 3, non-zero area).

    Non-adjacent edges may not touch; adjacent edges may only share their common vertex.
    """
    v = np.asarray(vertices, dtype=np.float64)
    k = v.shape[0]
    if k < 3 or abs(polygon_area(v)) <= 0.0:
        return False
    if np.any(np.all(v == np.roll(v, -1, axis=0), axis=1)):
        return False
    a = v
    b = np.roll(v, -1, axis=0)
    i, j = np.triu_indices(k, 1)
    adjacent = (j == i + 1) | ((i == 0) & (j == k - 1))
    touch = segments_touch(a[i], b[i], a[j], b[j])
    if np.any(touch & ~adjacent):
        return False
    # adjacent edges: they share one vertex; they overlap if collinear and folding back
    ia, ja = i[adjacent], j[adjacent]
    d1 = b[ia] - a[ia]
    d2 = b[ja] - a[ja]
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    dot = np.sum(d1 * d2, axis=1)
    scale = np.linalg.norm(d1, axis=1) * np.linalg.norm(d2, axis=1)
    folded = (np.abs(cross) <= 1e-12 * scale) & (dot < 0)
    return not bool(np.any(folded))


def polygon_area(vertices: ArrayLike) -> float:
    """Signed area of a closed polygon ``(k, 2)`` (positive when counter-clockwise)."""
    v = np.asarray(vertices, dtype=np.float64)
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def cross2(u: FloatArray, v: FloatArray) -> FloatArray:
    """z component of the cross product of 2D vectors, broadcasting ``(..., 2)`` -> ``(...)``."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def segments_touch(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> NDArray:
    """Closed segments ``ab`` and ``cd`` (broadcasting ``(..., 2)``) share at least one point."""
    o1 = np.sign(cross2(b - a, c - a))
    o2 = np.sign(cross2(b - a, d - a))
    o3 = np.sign(cross2(d - c, a - c))
    o4 = np.sign(cross2(d - c, b - c))
    proper = (o1 * o2 < 0) & (o3 * o4 < 0)

    def on(p: FloatArray, q: FloatArray, r: FloatArray, o: FloatArray) -> NDArray:
        return (
            (o == 0)
            & (np.minimum(p[..., 0], q[..., 0]) <= r[..., 0])
            & (r[..., 0] <= np.maximum(p[..., 0], q[..., 0]))
            & (np.minimum(p[..., 1], q[..., 1]) <= r[..., 1])
            & (r[..., 1] <= np.maximum(p[..., 1], q[..., 1]))
        )

    return proper | on(a, b, c, o1) | on(a, b, d, o2) | on(c, d, a, o3) | on(c, d, b, o4)


def even_odd(P: FloatArray, a: FloatArray, b: FloatArray) -> NDArray[np.bool_]:
    """Even-odd point-in-polygon of points ``(..., 2)`` for one polygon's edges ``a -> b``."""
    py = P[..., None, 1]
    cond = (a[:, 1] > py) != (b[:, 1] > py)
    dy = b[:, 1] - a[:, 1]
    xint = a[:, 0] + (py - a[:, 1]) * (b[:, 0] - a[:, 0]) / np.where(dy == 0, 1.0, dy)
    return np.sum(cond & (P[..., None, 0] < xint), axis=-1) % 2 == 1


def point_segment_distance(P: FloatArray, A: FloatArray, B: FloatArray) -> FloatArray:
    """Distance from points to segments, broadcasting ``P, A, B (..., d)`` -> ``(...)``."""
    ab = B - A
    denom = np.sum(ab * ab, axis=-1)
    t = np.sum((P - A) * ab, axis=-1) / np.where(denom > 0, denom, 1.0)
    t = np.clip(t, 0.0, 1.0)
    closest = A + t[..., None] * ab
    return np.linalg.norm(P - closest, axis=-1)
