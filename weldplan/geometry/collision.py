"""The collision judge: python-fcl checks of the torch tip against the part.

The torch tip is a sphere of radius = clearance; moving it along a segment sweeps a capsule. A
segment is free when that capsule does not touch the part's triangles. The grid is only a search
space; every path that leaves weldplan has been re-checked here (DESIGN.md).
"""

from __future__ import annotations

import logging
import math

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

log = logging.getLogger(__name__)

#: segments shorter than this (mm) are checked as a sphere at their midpoint's ends
_MIN_LENGTH = 1e-9


def _rotation_z_to(d: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation matrix taking +z to unit vector ``d`` (3,)."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(np.dot(z, d))
    if c > 1.0 - 1e-12:
        return np.eye(3)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])
    v = np.cross(z, d)
    s = np.linalg.norm(v)
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx * ((1 - c) / s**2)


class CollisionModel:
    """A BVH of the part's triangles for capsule and point checks.

    Parameters
    ----------
    mesh
        The part in mm.
    """

    def __init__(self, mesh: trimesh.Trimesh) -> None:
        self.mesh = mesh
        bvh = fcl.BVHModel()
        bvh.beginModel(len(mesh.vertices), len(mesh.faces))
        bvh.addSubModel(np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces))
        bvh.endModel()
        self._bvh = bvh
        self._part = fcl.CollisionObject(bvh, fcl.Transform())
        self._request = fcl.CollisionRequest()

    def __getstate__(self) -> dict:
        return {"mesh": self.mesh}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["mesh"])  # type: ignore[misc]

    def segment_free(self, a: ArrayLike, b: ArrayLike, radius: float) -> bool:
        """Whether a sphere of ``radius`` mm swept from ``a`` to ``b`` (3,) misses the part."""
        ax, ay, az = (float(v) for v in np.ravel(a)[:3])
        bx, by, bz = (float(v) for v in np.ravel(b)[:3])
        dx, dy, dz = bx - ax, by - ay, bz - az
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length < _MIN_LENGTH:
            geom = fcl.Sphere(radius)
            tf = fcl.Transform(np.array([ax, ay, az]))
        else:
            # quaternion (w, x, y, z) taking +z (the capsule's axis) to the segment's direction:
            # half-angle form of the rotation about z x d. Scalar maths: this check runs
            # thousands of times a pair, and small numpy calls cost 5x more than the FCL query.
            uz = dz / length
            w = 1.0 + uz
            if w < 1e-12:
                quat = np.array([0.0, 1.0, 0.0, 0.0])
            else:
                qx, qy = -dy / length, dx / length
                n = math.sqrt(w * w + qx * qx + qy * qy)
                quat = np.array([w / n, qx / n, qy / n, 0.0])
            geom = fcl.Capsule(radius, length)
            tf = fcl.Transform(quat, np.array([0.5 * (ax + bx), 0.5 * (ay + by), 0.5 * (az + bz)]))
        obj = fcl.CollisionObject(geom, tf)
        return fcl.collide(obj, self._part, self._request, fcl.CollisionResult()) == 0

    def segments_free(self, A: ArrayLike, B: ArrayLike, radius: float) -> NDArray[np.bool_]:
        """``(n,) bool`` for segments ``A[i] -> B[i]``, ``A`` and ``B`` of shape ``(n, 3)``."""
        A = np.asarray(A, dtype=np.float64).reshape(-1, 3)
        B = np.asarray(B, dtype=np.float64).reshape(-1, 3)
        return np.fromiter(
            (self.segment_free(a, b, radius) for a, b in zip(A, B, strict=True)),
            dtype=bool,
            count=len(A),
        )

    def path_free(self, points: ArrayLike, radius: float) -> bool:
        """Whether every segment of the polyline ``points (n, 3)`` is free."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        if len(P) == 1:
            return self.segment_free(P[0], P[0], radius)
        return bool(np.all(self.segments_free(P[:-1], P[1:], radius)))

    def clearance(self, points: ArrayLike) -> NDArray[np.float64]:
        """``(n,) float``: distance (mm) from each point ``(n, 3)`` to the part's surface."""
        P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        out = np.empty(len(P))
        req = fcl.DistanceRequest()
        probe = fcl.Sphere(1e-9)
        for i, p in enumerate(P):
            obj = fcl.CollisionObject(probe, fcl.Transform(p))
            out[i] = fcl.distance(obj, self._part, req, fcl.DistanceResult())
        return np.maximum(out, 0.0)
