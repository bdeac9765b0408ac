"""Path metrics shared by the 2D planners and the 3D torch routes.

Every function takes polylines ``(..., n, d)`` (any leading batch axes, any dimension d) and
reduces over the point axis, so a whole population of paths is measured in one call.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def segment_lengths(points: ArrayLike) -> FloatArray:
    """Lengths of the segments of polylines ``(..., n, d)``: ``(..., n - 1)``."""
    P = np.asarray(points, dtype=np.float64)
    d = np.diff(P, axis=-2)
    if d.shape[-1] == 2:  # the planar fast path
        return np.hypot(d[..., 0], d[..., 1])
    return np.linalg.norm(d, axis=-1)


def path_length(points: ArrayLike) -> FloatArray:
    """Total length of polylines ``(..., n, d)``: ``(...)`` (the sum of segment lengths)."""
    return np.sum(segment_lengths(points), axis=-1)


def turning_angles(points: ArrayLike) -> FloatArray:
    """Angle (radians, in ``[0, pi]``) between consecutive segments: ``(..., n - 2)``.

    Zero-length segments contribute no turn; "zero" is below the rounding of the coordinates
    (16 ulp of the largest one), so a segment that only rounding made non-zero turns nothing.
    """
    P = np.asarray(points, dtype=np.float64)
    d = np.diff(P, axis=-2)
    u = d[..., :-1, :]
    v = d[..., 1:, :]
    nu = np.linalg.norm(u, axis=-1)
    nv = np.linalg.norm(v, axis=-1)
    tol = 16 * np.finfo(np.float64).eps * (np.max(np.abs(P)) if P.size else 0.0)
    ok = (nu > tol) & (nv > tol)
    c = np.sum(u * v, axis=-1) / np.where(ok, nu * nv, 1.0)
    return np.where(ok, np.arccos(np.clip(c, -1.0, 1.0)), 0.0)


def smoothness(points: ArrayLike) -> FloatArray:
    """Sum of turning angles of polylines ``(..., n, d)`` in radians: ``(...)``.

    This is the sum in paper 003 eq. 12 (the arccos of the normalised dot product of
    consecutive segments); 0 for a straight path.
    """
    return np.sum(turning_angles(points), axis=-1)


def min_clearance(points: ArrayLike, clearance: Callable[[FloatArray], FloatArray]) -> FloatArray:
    """Smallest clearance over the points of polylines ``(..., n, d)``: ``(...)``.

    ``clearance`` maps points ``(..., d)`` to distances ``(...)`` (for example
    ``Obstacles2D.clearance`` or ``CollisionModel.clearance``); negative means inside.
    """
    return np.min(clearance(np.asarray(points, dtype=np.float64)), axis=-1)


def collision_count(
    points: ArrayLike, segments_hit: Callable[[FloatArray, FloatArray], NDArray[np.bool_]]
) -> NDArray[np.int64]:
    """Number of colliding segments of polylines ``(..., n, d)``: ``(...)``.

    ``segments_hit(A, B)`` maps segment ends ``(..., d)`` to ``(...) bool``.
    """
    P = np.asarray(points, dtype=np.float64)
    return np.sum(segments_hit(P[..., :-1, :], P[..., 1:, :]), axis=-1)


@dataclass(frozen=True)
class PathMetrics:
    """Metrics of one path.

    Attributes
    ----------
    length
        Polyline length (map units; mm in 3D).
    smoothness
        Sum of turning angles (radians).
    min_clearance
        Smallest distance to an obstacle over the path's points (negative: penetration).
    collisions
        Segments that enter an obstacle.
    n_points
        Points of the polyline.
    """

    length: float
    smoothness: float
    min_clearance: float
    collisions: int
    n_points: int

    @property
    def success(self) -> bool:
        """Collision-free."""
        return self.collisions == 0

    def to_json(self) -> str:
        return json.dumps(asdict(self), allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> PathMetrics:
        return cls(**json.loads(text))


def measure(points: ArrayLike, obstacles: Any) -> PathMetrics:
    """:class:`PathMetrics` of one polyline ``(n, d)`` against an obstacle model with
    ``clearance(points)`` and ``segments_hit(A, B)`` (``Obstacles2D``)."""
    P = np.asarray(points, dtype=np.float64)
    clear = obstacles.clearance
    hit = obstacles.segments_hit
    mc = float(min_clearance(P, clear)) if len(P) else float("inf")
    return PathMetrics(
        length=float(path_length(P)),
        smoothness=float(smoothness(P)),
        min_clearance=mc,
        collisions=int(collision_count(P, hit)),
        n_points=int(P.shape[0]),
    )
