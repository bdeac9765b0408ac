"""Brute-force geometry for tests: exact point-triangle distances in plain numpy.

Independent of open3d and fcl on purpose: the obstacle rule and the collision checks are tested
against this.
"""

from __future__ import annotations

import numpy as np


def point_triangle_distance(P: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """``(n, m)`` distances from points ``P (n, 3)`` to triangles ``tri (m, 3, 3)``.

    Ericson, Real-Time Collision Detection, 5.1.5 (closest point on triangle), vectorised.
    """
    P = np.asarray(P, dtype=np.float64)[:, None, :]
    a, b, c = (np.asarray(tri, dtype=np.float64)[None, :, k, :] for k in range(3))
    ab, ac, ap = b - a, c - a, P - a
    d1 = np.sum(ab * ap, -1)
    d2 = np.sum(ac * ap, -1)
    bp = P - b
    d3 = np.sum(ab * bp, -1)
    d4 = np.sum(ac * bp, -1)
    cp = P - c
    d5 = np.sum(ab * cp, -1)
    d6 = np.sum(ac * cp, -1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = vb / denom
        w = vc / denom
        closest = a + ab * v[..., None] + ac * w[..., None]  # interior
        # edge regions
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
    e_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    e_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    e_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    closest = np.where(e_bc[..., None], b + (c - b) * t_bc[..., None], closest)
    closest = np.where(e_ac[..., None], a + ac * t_ac[..., None], closest)
    closest = np.where(e_ab[..., None], a + ab * t_ab[..., None], closest)
    # vertex regions
    closest = np.where(((d6 >= 0) & (d5 <= d6))[..., None], c, closest)
    closest = np.where(((d3 >= 0) & (d4 <= d3))[..., None], b, closest)
    closest = np.where(((d1 <= 0) & (d2 <= 0))[..., None], a, closest)
    closest = np.broadcast_to(closest, np.broadcast_shapes(closest.shape, P.shape))
    return np.linalg.norm(P - closest, axis=-1)


def mesh_distance(P: np.ndarray, mesh, chunk: int = 2000) -> np.ndarray:
    """``(n,)`` distance from each point to the nearest triangle of a trimesh."""
    tri = np.asarray(mesh.triangles)
    P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
    out = np.empty(len(P))
    for s in range(0, len(P), chunk):
        out[s : s + chunk] = point_triangle_distance(P[s : s + chunk], tri).min(axis=1)
    return out


def winding_number(P: np.ndarray, mesh, chunk: int = 2000) -> np.ndarray:
    """``(n,)`` generalised winding number of a triangle mesh at each point (Jacobson, Kavan and
    Sorkine-Hornung 2013): the sum of the signed solid angles of the triangles over 4 pi, each
    by Van Oosterom and Strackee's formula. 1 inside a closed, outward-wound solid, 0 outside,
    k inside k nested or overlapping ones. Independent of open3d's and trimesh's ray parity."""
    tri = np.asarray(mesh.triangles, dtype=np.float64)
    P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
    out = np.empty(len(P))
    for s in range(0, len(P), chunk):
        a, b, c = (tri[None, :, k, :] - P[s : s + chunk, None, :] for k in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
        num = np.sum(a * np.cross(b, c), axis=-1)
        den = (
            la * lb * lc + np.sum(a * b, -1) * lc + np.sum(b * c, -1) * la + np.sum(c * a, -1) * lb
        )
        out[s : s + chunk] = 2.0 * np.arctan2(num, den).sum(axis=1) / (4.0 * np.pi)
    return out
