"""An independent route oracle: python-fcl on the raw triangles plus a winding-number inside test.

It shares nothing with weldplan's planner or verifier (no weldplan import at all): it reads the
route JSON as plain data and the mesh as raw triangles, and checks

* the route visits every joint of the joints file exactly once, legs chained end to start, each
  leg starting and ending on its joints' weld spots (within :data:`ENDPOINT_TOL` mm);
* every coordinate is finite;
* every segment, as a capsule of radius ``clearance`` (python-fcl ``Capsule`` against a
  ``BVHModel`` of the triangles), misses the part; a segment that starts or ends on a weld spot
  (a point closer than ``clearance`` to the part) is checked instead as the approach cone that
  weldplan/weld/verify.py documents: radius ``c * s / L`` at distance ``s`` from the spot,
  inscribed by :data:`CONE_PIECES` capsules from :data:`CONE_EXEMPT` mm on;
* no route point other than the weld spots lies inside a closed component of the part (the
  generalized winding number of the component's triangles is ``>= 0.5``). A free capsule crosses
  no triangle, so one point per segment decides the whole segment.

A mesh with a non-finite vertex cannot be checked: :func:`load_triangles` raises
:class:`Uncheckable`, and a route reported for such a mesh is a failure of the invariant.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import fcl
import numpy as np
import trimesh

#: mm: a leg's end may be this far from its joint's spot
ENDPOINT_TOL = 1e-3
#: capsules inscribing an approach cone, and the mm at the spot left unchecked
CONE_PIECES = 16
CONE_EXEMPT = 0.5
#: relative slack on the cone radius (touching contact at equality is allowed)
CONE_SLACK = 1e-3
#: mm: route coordinates beyond this are refused: fcl's double-precision capsule tests lose
#: their meaning far out (at 1e300 a capsule is "free" of anything); 10 km leaves them exact
MAX_COORD = 1e7


class Uncheckable(Exception):
    """The input cannot be checked (non-finite geometry, malformed route)."""


@dataclass
class Triangles:
    """A part as raw triangles (mm), its fcl BVH and its closed components."""

    vertices: np.ndarray  # (n, 3)
    faces: np.ndarray  # (m, 3)
    closed: list[np.ndarray] = field(default_factory=list)  # (k, 3, 3) triangles per component
    bvh: object = None

    def __post_init__(self) -> None:
        m = fcl.BVHModel()
        m.beginModel(len(self.vertices), len(self.faces))
        m.addSubModel(self.vertices.astype(np.float64), self.faces.astype(np.int64))
        m.endModel()
        self.bvh = fcl.CollisionObject(m, fcl.Transform())
        mesh = trimesh.Trimesh(self.vertices, self.faces, process=True)
        for comp in mesh.split(only_watertight=False):
            if comp.is_watertight and len(comp.faces) >= 4:
                self.closed.append(np.asarray(comp.triangles, dtype=np.float64))


def load_triangles(path: str | Path, scale: float = 1.0) -> Triangles:
    """The mesh file's raw triangles times ``scale`` (mm); :class:`Uncheckable` when non-finite."""
    loaded = trimesh.load(str(path), force="mesh", process=False)
    v = np.asarray(loaded.vertices, dtype=np.float64) * scale
    f = np.asarray(loaded.faces, dtype=np.int64)
    if len(f) == 0:
        raise Uncheckable(f"{path}: no triangles")
    if not np.all(np.isfinite(v[np.unique(f)])):
        raise Uncheckable(f"{path}: non-finite vertices")
    return Triangles(v, f)


def _quat_z_to(d: np.ndarray) -> np.ndarray:
    """Quaternion (w, x, y, z) rotating +z onto unit ``d`` (Rodrigues' half-angle form)."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(np.dot(z, d))
    if c < -1.0 + 1e-12:
        return np.array([0.0, 1.0, 0.0, 0.0])
    axis = np.cross(z, d)
    q = np.array([1.0 + c, *axis])
    return q / np.linalg.norm(q)


def capsule_free(tri: Triangles, a, b, radius: float) -> bool:
    """Whether the capsule of ``radius`` mm around segment ``a -> b`` misses every triangle."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    d = b - a
    L = float(np.linalg.norm(d))
    if L < 1e-9:
        obj = fcl.CollisionObject(fcl.Sphere(radius), fcl.Transform(a))
    else:
        tf = fcl.Transform(_quat_z_to(d / L), 0.5 * (a + b))
        obj = fcl.CollisionObject(fcl.Capsule(radius, L), tf)
    return fcl.collide(obj, tri.bvh, fcl.CollisionRequest(), fcl.CollisionResult()) == 0


#: mm: radius of the sphere that stands for a point in fcl's distance query
_PROBE = 1e-9


def point_distance(tri: Triangles, p) -> float:
    """Exact distance (mm) from point ``p`` to the triangles (0 when touching)."""
    obj = fcl.CollisionObject(fcl.Sphere(_PROBE), fcl.Transform(np.asarray(p, dtype=np.float64)))
    d = fcl.distance(obj, tri.bvh, fcl.DistanceRequest(), fcl.DistanceResult())
    return max(float(d) + _PROBE, 0.0) if d >= 0 else 0.0


def winding_numbers(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Generalized winding number of closed triangles ``(k, 3, 3)`` at ``points (m, 3)``.

    Van Oosterom and Strackee's solid angle of each triangle seen from each point, summed and
    divided by ``4 pi``: 1 inside a closed, outward-oriented surface, 0 outside (its absolute
    value is used, so inward orientation works too).
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.zeros(len(P))
    for start in range(0, len(triangles), 4096):
        T = triangles[start : start + 4096]
        A = T[None, :, 0, :] - P[:, None, :]
        B = T[None, :, 1, :] - P[:, None, :]
        C = T[None, :, 2, :] - P[:, None, :]
        a, b, c = (np.linalg.norm(X, axis=2) for X in (A, B, C))
        num = np.einsum("ijk,ijk->ij", A, np.cross(B, C))
        den = (
            a * b * c
            + np.einsum("ijk,ijk->ij", A, B) * c
            + np.einsum("ijk,ijk->ij", B, C) * a
            + np.einsum("ijk,ijk->ij", C, A) * b
        )
        out += np.sum(2.0 * np.arctan2(num, den), axis=1)
    return np.abs(out) / (4.0 * np.pi)


def inside_closed(tri: Triangles, points) -> np.ndarray:
    """``(m,) bool``: points inside any closed component of the part."""
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    inside = np.zeros(len(P), dtype=bool)
    for comp in tri.closed:
        inside |= winding_numbers(comp, P) >= 0.5
    return inside


def _cone_free(tri: Triangles, spot: np.ndarray, far: np.ndarray, clearance: float) -> bool:
    L = float(np.linalg.norm(far - spot))
    if L <= CONE_EXEMPT:
        return True
    s = np.linspace(CONE_EXEMPT, L, CONE_PIECES + 1)
    pts = spot + np.outer(s / L, far - spot)
    radii = clearance * s[:-1] / L * (1.0 - CONE_SLACK)
    return all(capsule_free(tri, pts[m], pts[m + 1], float(radii[m])) for m in range(CONE_PIECES))


def check_route(
    route: dict, tri: Triangles, joints: dict[str, np.ndarray], clearance: float
) -> list[str]:
    """Every problem the oracle finds with ``route`` (a route JSON as a dict); empty when ok.

    ``joints``: id -> spot (3,) mm as the joints file gives them (after units).
    """
    problems: list[str] = []
    if not (math.isfinite(clearance) and clearance > 0):
        raise Uncheckable(f"clearance {clearance}")
    order = [str(j) for j in route.get("order", [])]
    if sorted(order) != sorted(joints) or len(set(order)) != len(order):
        problems.append(f"order {order} is not every joint once ({sorted(joints)})")
    legs = route.get("legs", [])
    if len(order) > 1 and len(legs) != len(order) - 1:
        problems.append(f"{len(legs)} legs for {len(order)} joints")
    for k, leg in enumerate(legs):
        pts = np.asarray(leg["points"], dtype=np.float64).reshape(-1, 3)
        where = f"leg {k} ({leg['from']} -> {leg['to']})"
        if not np.all(np.isfinite(pts)) or np.max(np.abs(pts)) > MAX_COORD:
            problems.append(f"{where}: non-finite coordinates or beyond {MAX_COORD:g} mm")
            continue
        if k < len(order) - 1 and (leg["from"], leg["to"]) != (order[k], order[k + 1]):
            problems.append(f"{where}: not the order's leg {order[k]} -> {order[k + 1]}")
        for end, jid in ((pts[0], leg["from"]), (pts[-1], leg["to"])):
            spot = joints.get(str(jid))
            if spot is None or np.linalg.norm(end - spot) > ENDPOINT_TOL:
                problems.append(f"{where}: does not end on joint {jid}'s spot")
        n = len(pts) - 1
        for s in range(n):
            a, b = pts[s], pts[s + 1]
            a_spot = s == 0 and point_distance(tri, a) < clearance
            b_spot = s == n - 1 and point_distance(tri, b) < clearance
            if a_spot and b_spot:
                ok = _cone_free(tri, a, 0.5 * (a + b), clearance) and _cone_free(
                    tri, b, 0.5 * (a + b), clearance
                )
            elif a_spot:
                ok = _cone_free(tri, a, b, clearance)
            elif b_spot:
                ok = _cone_free(tri, b, a, clearance)
            else:
                ok = capsule_free(tri, a, b, clearance)
            if not ok:
                problems.append(f"{where}, segment {s}: touches the part at {clearance} mm")
        inner = pts[1:-1] if len(pts) > 2 else 0.5 * (pts[:1] + pts[-1:])
        if len(inner) and np.any(inside_closed(tri, inner)):
            problems.append(f"{where}: passes inside a closed component of the part")
    return problems


def read_joints_plain(path: str | Path, scale: float = 1.0) -> dict[str, np.ndarray]:
    """id -> (3,) spot from a simple comma CSV with a header naming id, x, y, z."""
    import csv

    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    return {r["id"].strip(): scale * np.array([float(r[k]) for k in ("x", "y", "z")]) for r in rows}


def check_route_file(
    route_json: str | Path,
    mesh: str | Path,
    joints_csv: str | Path,
    clearance: float,
    *,
    scale: float = 1.0,
    joint_scale: float = 1.0,
) -> list[str]:
    """:func:`check_route` from files (the joints CSV in the simple layout of the tests);
    ``scale`` multiplies the mesh, ``joint_scale`` the joints (mm per file unit)."""
    route = json.loads(Path(route_json).read_text(encoding="utf-8"))
    return check_route(
        route, load_triangles(mesh, scale), read_joints_plain(joints_csv, joint_scale), clearance
    )


def blend_curve(prev, corner, nxt, radius: float, samples: int = 17) -> np.ndarray:
    """``(samples, 3)`` points of the corner-cutting curve a controller flies through a zone.

    The TCP leaves the incoming segment ``radius`` mm before ``corner`` and joins the outgoing one
    ``radius`` mm after it (both capped at the segment's length); in between it follows the
    quadratic Bezier curve entry -> corner -> exit (a parabola; ABB and KUKA both document a
    parabolic or polynomial corner path within the zone). Any curve the controller may choose
    lies in the triangle entry-corner-exit, so within ``radius`` of the corner.
    """
    P = np.asarray(corner, dtype=np.float64)
    A = np.asarray(prev, dtype=np.float64)
    B = np.asarray(nxt, dtype=np.float64)
    la, lb = np.linalg.norm(A - P), np.linalg.norm(B - P)
    E = P + (A - P) * min(1.0, radius / la) if la > 0 else P
    X = P + (B - P) * min(1.0, radius / lb) if lb > 0 else P
    t = np.linspace(0.0, 1.0, samples)[:, None]
    return (1 - t) ** 2 * E + 2 * (1 - t) * t * P + t**2 * X
