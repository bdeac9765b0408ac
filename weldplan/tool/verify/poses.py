"""The independent re-check of weld poses: fresh FCL models, the whole part, a different test.

The pose search (:mod:`weldplan.tool.poses.plan`) checks the tool *minus its triangles inside the
contact zone* against the part *cropped* to the tool's reach, with cached BVHs and rotation
matrices it generated itself. This module shares none of that: for every pose it rebuilds the
transform from the reported quaternion and position, and checks against python-fcl models built
here from the whole part mesh and the whole tool mesh:

1. contact: ``fcl.collide`` of the **whole** tool against the whole part, with every contact
   returned; for each touching pair of triangles the points where they cross are computed here
   (:func:`triangle_crossings`; FCL's own contact position for mesh pairs can be a vertex away
   from the contact); the pose passes only if every crossing lies inside the contact zone (the
   sphere of ``contact_radius`` about the weld spot, and for a tool with a ``tip_cone``, within
   that angle of the tool's axis behind the spot) and FCL did not stop at its contact cap. A
   touching pair with no crossing (coplanar overlap) passes only if the whole tool triangle lies
   inside the zone;
2. clearance: ``fcl.distance`` between the tool outside the zone (recomputed here from the
   tool's raw mesh, :meth:`~weldplan.tool.model.Tool.outside_zone`) and the whole part is at
   least ``clearance`` (with ``clearance = 0``: they do not collide). This also catches a
   contact that FCL reports by one point inside the zone while the touching triangle pair
   reaches out of it.

Test 1 is a different formulation of the exemption than the search's (contact positions in
the part frame instead of tool triangles dropped in the tool frame), so a slip in either shows.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from weldplan.geometry.checker import CheckVerdict
from weldplan.tool.model.tool import Tool, bvh
from weldplan.tool.poses.result import WeldPoses

log = logging.getLogger(__name__)

#: contacts requested from FCL per pose; a pose that reaches the cap fails (cannot be checked)
MAX_CONTACTS = 200_000
#: slack (mm) on the contact-zone radius and the clearance for floating-point round-off
TOLERANCE_MM = 1e-6


@dataclass(frozen=True)
class PoseCheck:
    """Outcome of one pose's re-check: ``ok``, and in words why not; ``distance`` (mm) the FCL
    distance of the tool outside its zone to the part where it was measured (``nan``: not)."""

    ok: bool
    reason: str = ""
    distance: float = math.nan

    @property
    def verdict(self) -> CheckVerdict:
        """This check as a :class:`~weldplan.geometry.checker.CheckVerdict`."""
        fails = () if self.ok else (("", self.reason),)
        return CheckVerdict.of("tool pose", 1, fails, min_clearance=self.distance, ok=self.ok)


@dataclass(frozen=True)
class PosesVerification:
    """Outcome of :func:`verify_poses`: ``ok`` when every weld reported ok passed;
    ``min_clearance`` (mm) the least distance measured of the tool outside its zone to the part
    (``nan``: none measured)."""

    ok: bool
    checked: int
    failures: tuple[tuple[str, str], ...] = ()
    min_clearance: float = math.nan

    @property
    def verdict(self) -> CheckVerdict:
        """This check as a :class:`~weldplan.geometry.checker.CheckVerdict` (places: welds)."""
        return CheckVerdict.of(
            "tool poses", self.checked, self.failures, place="weld {}", ok=self.ok,
            min_clearance=self.min_clearance,
        )  # fmt: skip


class PoseChecker:
    """Fresh python-fcl models of a part and a tool for checking single poses.

    Parameters
    ----------
    part
        The part (mm).
    tool
        The tool (mm, TCP frame).
    contact_radius
        mm: the contact zone about the weld spot.
    clearance
        mm: the least distance between the tool outside the zone and the part.
    """

    def __init__(
        self, part: trimesh.Trimesh, tool: Tool, contact_radius: float, clearance: float
    ) -> None:
        self.contact_radius = float(contact_radius)
        self.clearance = float(clearance)
        self.tip_cone = tool.tip_cone
        self._part = fcl.CollisionObject(
            bvh(np.asarray(part.vertices), np.asarray(part.faces)), fcl.Transform()
        )
        self._part_tri = np.asarray(part.vertices, dtype=np.float64)[np.asarray(part.faces)]
        self._tool = fcl.CollisionObject(bvh(tool.vertices, tool.faces), fcl.Transform())
        self._tool_tri = tool.vertices[tool.faces]
        v, f = tool.outside_zone(self.contact_radius)
        self._outside = fcl.CollisionObject(bvh(v, f), fcl.Transform())

    def check(self, position: ArrayLike, quaternion: ArrayLike) -> PoseCheck:
        """Check the TCP at ``position (3,)`` mm with orientation ``(qw, qx, qy, qz)``."""
        p = np.asarray(position, dtype=np.float64).reshape(3)
        q = np.asarray(quaternion, dtype=np.float64).reshape(4)
        if abs(np.linalg.norm(q) - 1.0) > 1e-6:
            return PoseCheck(False, f"quaternion {q.tolist()} is not a unit quaternion")
        R = Rotation.from_quat(np.roll(q, -1)).as_matrix()  # scipy wants (x, y, z, w)
        tf = fcl.Transform(R, p)
        self._tool.setTransform(tf)
        req = fcl.CollisionRequest(num_max_contacts=MAX_CONTACTS, enable_contact=True)
        res = fcl.CollisionResult()
        n = fcl.collide(self._tool, self._part, req, res)
        if n >= MAX_CONTACTS:
            return PoseCheck(False, f"{n} contacts: too many to check")
        if n:
            b1 = np.array([c.b1 for c in res.contacts])
            b2 = np.array([c.b2 for c in res.contacts])
            A = self._tool_tri[b1] @ R.T + p
            B = self._part_tri[b2]
            pts, ok = triangle_crossings(A, B)
            flat = ~ok.any(axis=1)  # coplanar touch: the whole tool triangle must be inside
            X = np.concatenate([pts[ok], A[flat].reshape(-1, 3)])  # every touching point
            d = np.linalg.norm(X - p, axis=1)
            worst = int(np.argmax(d))
            if d[worst] > self.contact_radius + TOLERANCE_MM:
                return PoseCheck(
                    False,
                    f"tool touches the part {d[worst]:.1f} mm from the weld spot, outside the "
                    f"{self.contact_radius:g} mm contact zone",
                )
            if self.tip_cone is not None:
                # the angle at the spot between the tool's axis backwards (-R[:, 2]) and each
                # touching point: in the part frame, not the tool's zone test
                back = np.degrees(
                    np.arccos(np.clip(-(X - p) @ R[:, 2] / np.maximum(d, 1e-12), -1, 1))
                )
                off = int(np.argmax(np.where(d > TOLERANCE_MM, back, 0.0)))
                if d[off] > TOLERANCE_MM and back[off] > self.tip_cone + 1e-6:
                    return PoseCheck(
                        False,
                        f"tool touches the part {d[off]:.1f} mm from the weld spot, "
                        f"{back[off]:.0f} deg off its axis, outside the {self.tip_cone:g} deg "
                        "tip cone of its contact zone",
                    )
        self._outside.setTransform(tf)
        if self.clearance <= 0:
            if fcl.collide(
                self._outside, self._part, fcl.CollisionRequest(), fcl.CollisionResult()
            ):
                return PoseCheck(False, "tool outside the contact zone touches the part")
        else:
            dist = fcl.distance(
                self._outside, self._part, fcl.DistanceRequest(), fcl.DistanceResult()
            )
            if dist < self.clearance - TOLERANCE_MM:
                return PoseCheck(
                    False,
                    f"tool outside the contact zone is {max(dist, 0):.2f} mm from the part, "
                    f"less than the clearance {self.clearance:g} mm",
                    max(float(dist), 0.0),
                )
            return PoseCheck(True, distance=float(dist))
        return PoseCheck(True)


def triangle_crossings(A: ArrayLike, B: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Where the edges of triangles ``A[i]`` cross triangles ``B[i]`` and vice versa.

    Parameters
    ----------
    A, B
        ``(k, 3, 3)``: k pairs of triangles (mm).

    Returns
    -------
    points, valid
        ``(k, 6, 3)`` and ``(k, 6) bool``: for each pair, the crossings of A's three edges with
        B, then of B's three edges with A; for two triangles that intersect transversally the
        valid points are the ends of their intersection segment. Coplanar pairs have none.
    """
    A = np.asarray(A, dtype=np.float64).reshape(-1, 3, 3)
    B = np.asarray(B, dtype=np.float64).reshape(-1, 3, 3)
    pts, valid = [], []
    for s, t in ((A, B), (B, A)):
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])  # (k, 3)
        nn = np.einsum("ij,ij->i", n, n)
        p0, p1 = s, np.roll(s, -1, axis=1)  # edges (k, 3, 3)
        d0 = np.einsum("kej,kj->ke", p0 - t[:, None, 0], n)
        d1 = np.einsum("kej,kj->ke", p1 - t[:, None, 0], n)
        cross = (d0 * d1 <= 0) & (d0 != d1) & (nn[:, None] > 0)
        u = np.divide(d0, d0 - d1, out=np.zeros_like(d0), where=d0 != d1)
        x = p0 + u[..., None] * (p1 - p0)
        t1 = np.roll(t, -1, axis=1)
        # inside t: each edge function has the sign of the normal
        inside = np.ones(cross.shape, dtype=bool)
        for i in range(3):
            edge = t1[:, i] - t[:, i]  # (k, 3)
            w = np.cross(edge[:, None, :], x - t[:, None, i])  # (k, 3, 3)
            inside &= np.einsum("kej,kj->ke", w, n) >= -1e-9 * nn[:, None]
        pts.append(x)
        valid.append(cross & inside)
    return np.concatenate(pts, axis=1), np.concatenate(valid, axis=1)


def verify_poses(
    poses: WeldPoses,
    part: trimesh.Trimesh,
    tool: Tool,
    *,
    contact_radius: float | None = None,
    clearance: float | None = None,
) -> PosesVerification:
    """Re-check every weld reported ok in ``poses`` with fresh FCL models (module docstring).

    ``contact_radius`` and ``clearance`` default to the values in ``poses.settings``.
    """
    r = float(poses.settings["contact_radius"] if contact_radius is None else contact_radius)
    c = float(poses.settings["clearance"] if clearance is None else clearance)
    checker = PoseChecker(part, tool, r, c)
    failures = []
    checked = 0
    least = math.nan
    for wp in poses.poses:
        if not wp.ok:
            continue
        checked += 1
        if wp.quaternion is None:
            failures.append((wp.id, "reported ok without an orientation"))
            continue
        out = checker.check(wp.position, wp.quaternion)
        least = out.distance if math.isnan(least) else min(least, out.distance)
        if not out.ok:
            failures.append((wp.id, out.reason))
    return PosesVerification(not failures, checked, tuple(failures), least)
