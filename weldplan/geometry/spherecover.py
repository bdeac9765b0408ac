"""Spheres that hold a triangle mesh: the broad phase of the robot's and the tool's swept checks.

A sphere's distance to the part is its centre's distance less its radius, one point query
(:class:`~weldplan.geometry.distbound.DistanceBound`), where a mesh's distance needs a BVH
traversal: the covers let most far-away bodies be cleared without FCL.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def sphere_cover(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], cell: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Spheres ``(s, 3)`` centres, ``(s,)`` radii (mm) whose union holds every triangle: the
    triangles are grouped by the grid cell of their centroid, each group's sphere is centred on
    its vertices' bounding-box centre and reaches its farthest vertex (a ball is convex, so it
    holds the triangles whose corners it holds). Also returns each triangle's sphere ``(m,)``."""
    tri = vertices[faces]  # (m, 3, 3)
    key = np.floor(tri.mean(axis=1) / cell).astype(np.int64)
    _, group = np.unique(key, axis=0, return_inverse=True)
    group = group.ravel()
    g = int(group.max()) + 1
    pts = tri.reshape(-1, 3)
    pg = np.repeat(group, 3)
    lo = np.full((g, 3), np.inf)
    hi = np.full((g, 3), -np.inf)
    np.minimum.at(lo, pg, pts)
    np.maximum.at(hi, pg, pts)
    centres = (lo + hi) / 2
    r = np.zeros(g)
    np.maximum.at(r, pg, np.linalg.norm(pts - centres[pg], axis=1))
    return centres, r * (1 + 1e-9) + 1e-9, group.astype(np.int64)
