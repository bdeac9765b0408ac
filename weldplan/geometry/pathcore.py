"""The path core shared by the 3D torch routes and the 2D planar maps: one obstacle protocol and
the polyline operations on ``(n, d)`` arrays of any dimension ``d``.

An obstacle model, in any dimension, answers two questions (:class:`PathObstacle`):

``distance(points (m, d)) -> (m,)``
    distance (mm in 3D, map units in 2D) from each point to the nearest obstacle surface;
``segments_free(A (m, d), B (m, d), radius) -> (m,) bool``
    whether a ball of ``radius`` swept along each segment ``A[k] -> B[k]`` misses every obstacle.

The 3D part (:class:`weldplan.geometry.collision.CollisionModel`, python-fcl + open3d) implements it
as it is; the 2D maps implement it through
:class:`weldplan.geometry.planar_obstacle.PlanarObstacle`.
The continuous refinement (:mod:`weldplan.weld.refine`) and the smooth paths
(:mod:`weldplan.geometry.smooth`) see only this protocol.

Lengths and metrics over batches of paths live in :mod:`weldplan.geometry.pathmetrics`; this module
adds what one path needs: arc length, points at arc length, resampling.
"""

from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.pathmetrics import segment_lengths

FloatArray = NDArray[np.float64]

__all__ = [
    "PathObstacle",
    "arc_lengths",
    "as_path",
    "at_fractions",
    "point_at",
    "polyline_length",
    "resample_count",
    "resample_even",
    "segment_free",
    "split_segments",
]


@runtime_checkable
class PathObstacle(Protocol):
    """An obstacle model in R^d (module docstring)."""

    def distance(self, points: FloatArray) -> FloatArray:
        """``(m,)`` distance from each point ``(m, d)`` to the nearest obstacle surface."""
        ...

    def segments_free(self, A: FloatArray, B: FloatArray, radius: float) -> NDArray[np.bool_]:
        """``(m,) bool``: the ball of ``radius`` swept along ``A[k] -> B[k]`` misses everything."""
        ...


def segment_free(obstacle: PathObstacle, a: ArrayLike, b: ArrayLike, radius: float) -> bool:
    """Whether the ball of ``radius`` swept from ``a`` to ``b`` (``(d,)``) is free."""
    A = np.asarray(a, dtype=np.float64).reshape(1, -1)
    B = np.asarray(b, dtype=np.float64).reshape(1, -1)
    return bool(obstacle.segments_free(A, B, radius)[0])


def as_path(points: ArrayLike, d: int | None = None) -> FloatArray:
    """``points`` as a float ``(n, d)`` array (a ``(d,)`` point gives ``(1, d)``).

    Raises
    ------
    ValueError
        When the points are not ``(n, d)`` (or not of dimension ``d`` when it is given), or not
        finite.
    """
    P = np.asarray(points, dtype=np.float64)
    if P.ndim == 1:
        P = P.reshape(1, -1)
    if P.ndim != 2 or (d is not None and P.shape[1] != d):
        want = f"(n, {d})" if d is not None else "(n, d)"
        raise ValueError(f"a path must be {want} points, got shape {P.shape}")
    if not np.all(np.isfinite(P)):
        raise ValueError("a path must have finite coordinates")
    return P


def polyline_length(points: ArrayLike) -> float:
    """Length of one polyline ``(n, d)`` (the sum of its segment lengths; 0 below 2 points)."""
    P = np.asarray(points, dtype=np.float64)
    if P.ndim != 2 or len(P) < 2:
        return 0.0
    return float(segment_lengths(P).sum())


def arc_lengths(points: ArrayLike) -> FloatArray:
    """``(n,)`` cumulative arc length at each vertex of ``points (n, d)`` (starts at 0)."""
    P = np.asarray(points, dtype=np.float64)
    out = np.zeros(len(P))
    if len(P) > 1:
        np.cumsum(segment_lengths(P), out=out[1:])
    return out


def point_at(points: ArrayLike, s: ArrayLike) -> FloatArray:
    """Points at arc lengths ``s (m,)`` along the polyline ``points (n, d)``: ``(m, d)``.

    ``s`` is clipped to ``[0, length]``; a vertex's own arc length gives the vertex exactly.
    """
    P = np.asarray(points, dtype=np.float64)
    S = arc_lengths(P)
    s = np.clip(np.asarray(s, dtype=np.float64).reshape(-1), 0.0, S[-1])
    k = np.clip(np.searchsorted(S, s, side="right") - 1, 0, max(len(P) - 2, 0))
    if len(P) < 2:
        return np.repeat(P[:1], len(s), axis=0)
    seg = S[k + 1] - S[k]
    t = np.divide(s - S[k], seg, out=np.zeros_like(s), where=seg > 0)
    out = P[k] + t[:, None] * (P[k + 1] - P[k])
    exact = np.isclose(t, 1.0, rtol=0.0, atol=0.0)
    out[exact] = P[k[exact] + 1]
    return out


def _norm_arc_lengths(P: FloatArray) -> FloatArray:
    """Cumulative arc length of ``P (n, d)`` with :func:`numpy.linalg.norm` in every dimension
    (see :func:`at_fractions`)."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])


def _interp(P: FloatArray, S: FloatArray, s: FloatArray) -> FloatArray:
    """Each coordinate of ``P`` interpolated at arc lengths ``s (...)`` (:func:`numpy.interp`,
    clamped to the ends): ``(..., d)``."""
    return np.stack([np.interp(s, S, P[:, i]) for i in range(P.shape[1])], axis=-1)


def at_fractions(points: ArrayLike, q: ArrayLike) -> FloatArray:
    """Points at the fractions ``q`` (any shape ``(...)``, in ``[0, 1]``) of the arc length of
    ``points (n, d)``: ``(..., d)``, each coordinate interpolated with :func:`numpy.interp`.

    This is how the planar encodings seed nodes along a path (roadmap seeding, the spline
    encoding's optimum). The arc length here is summed from :func:`numpy.linalg.norm` of each
    segment in every dimension, as those callers always did; :func:`arc_lengths` uses
    :func:`~weldplan.geometry.pathmetrics.segment_lengths`, whose 2D fast path (``hypot``)
    differs from it in the last bit on about one segment in six, so the two are kept apart to
    keep the planar planners' seeded outputs bit for bit. :func:`point_at` rounds differently
    again (it returns a vertex exactly at its own arc length).
    """
    P = np.asarray(points, dtype=np.float64)
    S = _norm_arc_lengths(P)
    return _interp(P, S, np.asarray(q, dtype=np.float64) * S[-1])


def resample_even(points: ArrayLike, n: int) -> FloatArray:
    """``n`` points at even arc-length steps along ``points (k, d)``, both ends included (the
    arc length and interpolation of :func:`at_fractions`)."""
    P = np.asarray(points, dtype=np.float64)
    S = _norm_arc_lengths(P)
    return _interp(P, S, np.linspace(0.0, S[-1], int(n)))


def split_segments(points: ArrayLike, step: float) -> FloatArray:
    """Split every segment longer than ``step`` into equal pieces no longer than ``step``.

    The vertices are kept bit for bit; this is the split of step 9 of Wang et al. 2017's
    secondary optimisation (section 4.3).

    Returns
    -------
    ``(m, d)`` with ``m >= n``.
    """
    P = np.asarray(points, dtype=np.float64)
    if len(P) < 2:
        return P.copy()
    L = segment_lengths(P)
    pieces = np.maximum(1, np.ceil(L / float(step) - 1e-9).astype(np.int64))
    out = [P[:1]]
    for a, b, n in zip(P[:-1], P[1:], pieces, strict=True):
        if n > 1:
            t = np.arange(1, n, dtype=np.float64)[:, None] / n
            out.append(a + t * (b - a))
        out.append(b[None])  # the vertex itself, bit for bit
    return np.concatenate(out)


def resample_count(points: ArrayLike, n: int) -> FloatArray:
    """``n`` points spaced evenly by arc length along ``points (k, d)``, both ends included."""
    P = np.asarray(points, dtype=np.float64)
    n = int(n)
    if n < 2:
        raise ValueError(f"resample to at least 2 points, got {n}")
    total = polyline_length(P)
    out = point_at(P, np.linspace(0.0, total, n))
    out[0], out[-1] = P[0], P[-1]
    return out


def pieces_for(length: float, step: float) -> int:
    """Pieces of at most ``step`` that cover ``length`` (at least 1)."""
    return max(1, math.ceil(float(length) / float(step) - 1e-9))
