"""The 2D maps as a :class:`~weldplan.geometry.pathcore.PathObstacle`: a thin adapter over
:class:`~weldplan.geometry.obstacles2d.Obstacles2D` (which it does not change), so the continuous
refinement and the smooth paths of the 3D torch routes run on planar maps as they are.

``distance(points)``
    ``Obstacles2D.clearance``: signed distance to the nearest obstacle (negative inside).
``segments_free(A, B, radius)``
    ``radius == 0``: ``Obstacles2D.segments_free`` (the planners' own rule, with its grazing
    tolerance). ``radius > 0``: the disc of ``radius`` swept along the segment misses every
    obstacle, exactly: the segment does not enter an obstacle, and its distance to every
    circle centre is at least the circle's radius + ``radius`` and to every polygon edge
    (rectangles as polygons) at least ``radius``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.obstacles2d import Obstacles2D, point_segment_distance

FloatArray = NDArray[np.float64]

__all__ = ["PlanarObstacle", "segment_segment_distance"]


def _cross(u: FloatArray, v: FloatArray) -> FloatArray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def segment_segment_distance(
    A: FloatArray, B: FloatArray, C: FloatArray, D: FloatArray
) -> FloatArray:
    """Distance between planar segments ``A -> B`` and ``C -> D`` (broadcast ``(..., 2)``): 0 when
    they cross, else the least of the four end-point-to-segment distances."""
    A, B, C, D = np.broadcast_arrays(A, B, C, D)
    d1, d2 = _cross(B - A, C - A), _cross(B - A, D - A)
    d3, d4 = _cross(D - C, A - C), _cross(D - C, B - C)
    cross = (d1 * d2 < 0) & (d3 * d4 < 0)
    lead = A.shape[:-1]

    def psd(P: FloatArray, S0: FloatArray, S1: FloatArray) -> FloatArray:
        return point_segment_distance(P.reshape(-1, 2), S0.reshape(-1, 2), S1.reshape(-1, 2))

    d = np.minimum.reduce([psd(A, C, D), psd(B, C, D), psd(C, A, B), psd(D, A, B)]).reshape(lead)
    return np.where(cross, 0.0, d)


@dataclass(frozen=True)
class PlanarObstacle:
    """:class:`Obstacles2D` seen through the path-core protocol (module docstring)."""

    obstacles: Obstacles2D
    _edges: tuple[FloatArray, FloatArray] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        polys = list(self.obstacles.polygons)
        for x0, y0, x1, y1 in np.asarray(self.obstacles.rectangles).reshape(-1, 4):
            polys.append(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=np.float64))
        if polys:
            E0 = np.concatenate([np.asarray(p, dtype=np.float64) for p in polys])
            E1 = np.concatenate(
                [np.roll(np.asarray(p, dtype=np.float64), -1, axis=0) for p in polys]
            )
        else:
            E0 = E1 = np.zeros((0, 2))
        object.__setattr__(self, "_edges", (E0, E1))

    def distance(self, points: ArrayLike) -> FloatArray:
        """``(m,)``: signed distance from points ``(m, 2)`` to the nearest obstacle."""
        return np.asarray(self.obstacles.clearance(np.asarray(points, dtype=np.float64)))

    def segments_free(self, A: ArrayLike, B: ArrayLike, radius: float) -> NDArray[np.bool_]:
        """``(m,) bool``: the disc of ``radius`` swept along ``A[k] -> B[k]`` misses everything."""
        A = np.asarray(A, dtype=np.float64).reshape(-1, 2)
        B = np.asarray(B, dtype=np.float64).reshape(-1, 2)
        free = np.asarray(self.obstacles.segments_free(A, B), dtype=bool)
        r = float(radius)
        if r <= 0 or len(A) == 0:
            return free
        # the segment may lie wholly inside a polygon or circle: its end point decides that
        free &= self.distance(A) >= r
        circles = np.asarray(self.obstacles.circles).reshape(-1, 3)
        if len(circles):
            d = point_segment_distance(
                np.broadcast_to(circles[None, :, :2], (len(A), len(circles), 2)).reshape(-1, 2),
                np.repeat(A, len(circles), axis=0),
                np.repeat(B, len(circles), axis=0),
            ).reshape(len(A), len(circles))
            free &= np.all(d >= circles[None, :, 2] + r, axis=1)
        E0, E1 = self._edges
        if len(E0):
            d = segment_segment_distance(A[:, None], B[:, None], E0[None], E1[None])
            free &= np.all(d >= r, axis=1)
        return free
