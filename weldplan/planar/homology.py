"""Distinctness of planar paths for ParaPA's multimodal planning (paper 003): the homology test
(winding numbers round one reference point per obstacle), the eq. 17 segment-crossing count and
its cross function, and a sampled Hausdorff distance. :mod:`weldplan.planar.multimodal`'s
docstring says why "distinct" means "in different homology classes" and names the readings.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.obstacles2d import Obstacles2D
from weldplan.geometry.pathcore import resample_even
from weldplan.geometry.primitives2d import segments_touch
from weldplan.optim.algorithms.parapa import CrossFunction
from weldplan.planar.encodings import SegmentPathProblem

FloatArray = NDArray[np.float64]

#: points per path for the sampled Hausdorff distance (reported, not used for decisions)
HAUSDORFF_SAMPLES = 200


def reference_points(obstacles: Obstacles2D) -> FloatArray:
    """One point strictly inside each obstacle, ``(O, 2)``: circle and rectangle centres, and
    for a polygon the midpoint of the first interior stretch of a horizontal line through it
    (at a height between two vertex heights, so it meets no vertex; works for concave ones)."""
    pts = [
        obstacles.circles[:, :2],
        0.5 * (obstacles.rectangles[:, :2] + obstacles.rectangles[:, 2:]),
    ]
    poly = []
    for p in obstacles.polygons:
        ys = np.unique(p[:, 1])
        y = 0.5 * (ys[len(ys) // 2 - 1] + ys[len(ys) // 2]) if len(ys) > 1 else ys[0]
        a, b = p, np.roll(p, -1, axis=0)
        cross = (a[:, 1] > y) != (b[:, 1] > y)
        xs = a[cross, 0] + (y - a[cross, 1]) * (b[cross, 0] - a[cross, 0]) / (
            b[cross, 1] - a[cross, 1]
        )
        xs = np.sort(xs)
        poly.append([0.5 * (xs[0] + xs[1]), y])
    if poly:
        pts.append(np.asarray(poly, dtype=np.float64))
    return np.concatenate(pts).reshape(-1, 2)


def swept_angles(paths: ArrayLike, points: ArrayLike) -> FloatArray:
    """Angle (radians, signed) that the vector from each point to a traveller sweeps while
    the traveller follows each path: ``paths (..., n, 2)``, ``points (O, 2)`` -> ``(..., O)``.

    For two paths with the same ends, ``(sweep_a - sweep_b) / (2 pi)`` is the winding number
    of the loop ``a`` then ``b`` reversed around the point (an integer up to rounding)."""
    P = np.asarray(paths, dtype=np.float64)
    Q = np.asarray(points, dtype=np.float64)
    d = P[..., :, None, :] - Q  # (..., n, O, 2)
    step = np.diff(np.arctan2(d[..., 1], d[..., 0]), axis=-2)
    # each segment turns the vector by less than pi (unless it passes through the point)
    return np.sum((step + np.pi) % (2.0 * np.pi) - np.pi, axis=-2)


def class_differs(sweep_a: ArrayLike, sweep_b: ArrayLike) -> NDArray[np.bool_]:
    """Whether paths of sweeps ``(..., O)`` lie in different homology classes (broadcasting):
    some obstacle has a non-zero winding number of the loop between them."""
    d = (np.asarray(sweep_a) - np.asarray(sweep_b)) / (2.0 * math.pi)
    return np.any(np.rint(d) != 0, axis=-1)


def path_crossings(A: ArrayLike, B: ArrayLike) -> NDArray[np.int64]:
    """Eq. 17's cross values: for polylines ``A (m, n, 2)`` and ``B (E, p, 2)`` with the same
    start and goal, the number of (segment of a, segment of b) pairs that touch, ``(m, E)``.

    The first segments always touch at the common start and the last at the common goal;
    those two pairs are not counted. Identical paths count about three per segment."""
    A = np.asarray(A, dtype=np.float64)
    B = np.asarray(B, dtype=np.float64)
    a0, a1 = A[:, None, :-1, None, :], A[:, None, 1:, None, :]
    b0, b1 = B[None, :, None, :-1, :], B[None, :, None, 1:, :]
    touch = segments_touch(a0, a1, b0, b1)  # (m, E, n - 1, p - 1)
    count = touch.sum(axis=(2, 3)).astype(np.int64)
    same_start = np.all(A[:, None, 0] == B[None, :, 0], axis=-1)
    same_goal = np.all(A[:, None, -1] == B[None, :, -1], axis=-1)
    return count - same_start - same_goal


def hausdorff(a: ArrayLike, b: ArrayLike, samples: int = HAUSDORFF_SAMPLES) -> float:
    """Symmetric Hausdorff distance between two polylines sampled at ``samples`` points each
    by arc length (map units; reported, not used for decisions)."""
    pa = resample_even(np.asarray(a, float), samples)
    pb = resample_even(np.asarray(b, float), samples)
    d = np.linalg.norm(pa[:, None] - pb[None], axis=-1)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def crossing_cross(problem: SegmentPathProblem) -> CrossFunction:
    """Eq. 17 as a ParaPA cross function on ``problem``'s variables: for each candidate the
    crossings (:func:`path_crossings`) with all the elites summed, ``(m,) float``."""

    def cross(candidates: FloatArray, elites: FloatArray) -> FloatArray:
        c = path_crossings(problem.decode(candidates), problem.decode(elites))
        return c.sum(axis=1).astype(np.float64)

    return cross
