"""The swept tool: a conservative clearance check of a rigid tool moving between two poses.

Motion model. Between two TCP poses ``(p0, R0)`` and ``(p1, R1)`` the TCP moves on the straight
segment and the orientation turns at constant rate about one axis (spherical linear
interpolation, :class:`scipy.spatial.transform.Slerp`)::

    p(s) = p0 + s (p1 - p0),   R(s) = R0 exp(s theta k^),   s in [0, 1]

with ``theta`` (rad) the angle between ``R0`` and ``R1``. A tool point ``x`` (TCP frame, mm,
``|x| <= r`` with ``r`` the tool's reach) lands at ``w(s) = R(s) x + p(s)``; its speed in ``s``
is at most ``|p1 - p0| + theta r`` (the rotation moves it at ``theta`` times its distance from
the rotation axis through the TCP, at most ``theta r``). So between two parameters ``s`` and
``s'`` no tool point moves more than ``L |s - s'|`` with the **motion bound**
``L = |p1 - p0| + theta r`` (:func:`motion_bound`).

The check (:meth:`SweepChecker.check`) is conservative advancement on FCL distances: at ``s``
the **slack** (the distance from the tool to the part less the clearance, python-fcl
``distance``) is measured; no point of the tool can use it up before ``s + slack / L``, so the
next sample is taken there. It advances from the start to the middle and from the end back to
the middle (a weld pose may have little slack, which grows as the tool leaves it). A negative or
zero slack, more than ``2 (L / min_step + 1)`` samples (a motion that grazes the part), or,
from an end that is not a weld pose, a slack below ``min_step``, stops the check: the motion is
reported blocked at ``s``. A passed motion keeps **at least the
clearance from the part at every ``s``**, not only at the samples: that is what the independent
re-check (:mod:`weldplan.tool.verify_sweeps`) tests with its own uniform samples and its own
bound.

The contact zone. At a weld the tool's electrode cap (or wire tip) touches the sheet: the pose
search exempts the tool inside the sphere of ``contact_radius`` about the TCP
(:meth:`~weldplan.tool.model.Tool.outside_zone`) against the whole part. A motion that leaves or
reaches a weld narrows that exemption to pairs of tool-zone and part-zone points: the tool
outside its zone must keep the clearance from the whole part, and the tool inside its zone must
not touch the part outside the sphere of ``contact_radius`` about the weld spot (part frame; no
clearance asked there, because the pose itself may have the electrode cap within the clearance
of the sheet just outside that sphere). So an electrode cap may slide off its spot, but no other
part of the tool may pass through the sheet there (a C-gun's fixed electrode, 47 mm ahead of the
TCP, retracted along the tool axis, hits the sheet it straddles).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from weldplan.tool.model import ZONE_EDGE_MM, Tool, bvh

log = logging.getLogger(__name__)

#: mm: a motion of bound ``L`` may take at most ``2 (L / min_step + 1)`` samples (conservative
#: advancement along a motion that grazes the part would never end)
DEFAULT_MIN_STEP = 0.5


def quat_to_matrix(q: ArrayLike) -> NDArray[np.float64]:
    """``(..., 3, 3)`` rotation matrices of unit quaternions ``(..., 4)`` ``(qw, qx, qy, qz)``."""
    q = np.asarray(q, dtype=np.float64)
    return (
        Rotation.from_quat(np.roll(q.reshape(-1, 4), -1, axis=1))
        .as_matrix()
        .reshape((*q.shape[:-1], 3, 3))
    )


def rotation_angle(q0: ArrayLike, q1: ArrayLike) -> float:
    """Radians between two unit quaternions (any sign): ``2 arccos |q0 . q1|``."""
    dot = abs(float(np.dot(np.asarray(q0, dtype=np.float64), np.asarray(q1, dtype=np.float64))))
    return 2.0 * math.acos(min(1.0, dot))


def interpolate(
    p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike, s: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Poses along the motion (module docstring) at parameters ``s (k,)`` in [0, 1].

    Returns
    -------
    positions, rotations
        ``(k, 3)`` mm and ``(k, 3, 3)``.
    """
    s = np.atleast_1d(np.asarray(s, dtype=np.float64))
    a, b = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
    pos = a + s[:, None] * (b - a)
    ra = Rotation.from_quat(np.roll(np.asarray(q0, dtype=np.float64), -1))
    rb = Rotation.from_quat(np.roll(np.asarray(q1, dtype=np.float64), -1))
    rel = (ra.inv() * rb).as_rotvec()  # the shortest rotation from a to b, in a's frame
    rots = (ra * Rotation.from_rotvec(s[:, None] * rel[None, :])).as_matrix()
    return pos, rots


def motion_bound(p0: ArrayLike, q0: ArrayLike, p1: ArrayLike, q1: ArrayLike, reach: float) -> float:
    """mm: no tool point moves farther than this over the whole motion (module docstring)."""
    dp = float(np.linalg.norm(np.asarray(p1, dtype=np.float64) - np.asarray(p0, dtype=np.float64)))
    return dp + rotation_angle(q0, q1) * float(reach)


def tool_zone(tool: Tool, radius: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The tool's triangles that reach into the sphere of ``radius`` about the TCP (a superset of
    the tool inside it: every triangle whose closest point to the TCP lies within ``radius``).

    Returns ``(vertices (k, 3) mm, faces (j, 3))``, possibly empty.
    """
    tri = tool.vertices[tool.faces]
    closest = trimesh.triangles.closest_point(tri, np.zeros((len(tri), 3)))
    near = np.flatnonzero(np.linalg.norm(closest, axis=1) <= radius)
    f = tool.faces[near]
    used, inv = np.unique(f, return_inverse=True)
    return tool.vertices[used], inv.reshape(-1, 3).astype(np.int64)


def _reaching(tri: NDArray[np.float64], c: NDArray[np.float64], radius: float) -> NDArray[np.bool_]:
    """``(m,) bool``: triangles ``(m, 3, 3)`` whose closest point to ``c`` lies within ``radius``
    (a large triangle can cover the sphere with all its vertices outside)."""
    edge = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    vmin = np.linalg.norm(tri - c, axis=2).min(axis=1)
    out = np.zeros(len(tri), dtype=bool)
    cand = np.flatnonzero(vmin < radius + edge)  # every point of a triangle is within its
    if len(cand):  # longest edge of a vertex: a cheap superset first
        cp = trimesh.triangles.closest_point(tri[cand], np.repeat(c[None], len(cand), axis=0))
        out[cand] = np.linalg.norm(cp - c, axis=1) < radius
    return out


def outside_sphere(
    vertices: ArrayLike, faces: ArrayLike, centre: ArrayLike, radius: float
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """A mesh minus its parts inside the sphere of ``radius`` mm about ``centre (3,)``.

    The triangles that reach into the sphere (:func:`_reaching`) are subdivided (trimesh
    midpoint subdivision) until those still reaching in have their longest edge below
    :data:`~weldplan.tool.model.ZONE_EDGE_MM`; then the triangles wholly inside are dropped. The
    result covers every point of the mesh outside the sphere and reaches at most
    ``ZONE_EDGE_MM`` into it (conservative). Only the reaching triangles are subdivided.
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    c = np.asarray(centre, dtype=np.float64).reshape(3)
    if radius <= 0 or len(f) == 0:
        return v.copy(), f.copy()
    near = _reaching(v[f], c, radius)
    keep_f = f[~near]
    nv, nf = v, f[near]
    for _ in range(64):
        tri = nv[nf]
        inside = np.linalg.norm(tri - c, axis=2).max(axis=1) < radius
        reach = _reaching(tri, c, radius) & ~inside
        edges = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
        coarse = np.flatnonzero(reach & (edges > ZONE_EDGE_MM))
        if len(coarse) == 0:
            nf = nf[~inside]
            break
        nv, nf = trimesh.remesh.subdivide(nv, nf, face_index=coarse)
    # nv extends v (subdivision appends vertices), so the far faces keep their indices
    allf = np.concatenate([keep_f, nf])
    used = np.unique(allf)
    remap = np.full(len(nv), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return nv[used], remap[allf]


@dataclass(frozen=True)
class SweepCheck:
    """Outcome of one motion's check.

    Attributes
    ----------
    ok
        The tool keeps ``clearance`` from the part along the whole motion.
    samples
        FCL distance samples taken.
    min_slack
        mm: the least :meth:`SweepChecker.slack` measured at a sample (``inf``: nothing near).
    blocked_at
        The motion parameter in [0, 1] where the check stopped (NaN when ``ok``).
    bound
        mm: the motion bound ``L``.
    """

    ok: bool
    samples: int
    min_slack: float
    blocked_at: float = float("nan")
    bound: float = 0.0

    def describe(self) -> str:
        if self.ok:
            return f"free ({self.samples} samples, least slack {self.min_slack:.1f} mm)"
        how = "collides or lacks clearance" if self.min_slack < 0 else "grazes: sample budget spent"
        return f"blocked at {100 * self.blocked_at:.0f} % of the motion ({how})"


class SweepChecker:
    """The planner's swept-tool checker: python-fcl models of the part and the tool, kept.

    Parameters
    ----------
    part
        The part (mm).
    tool
        The tool (mm, TCP frame).
    clearance
        mm: the least distance the moving tool must keep from the part.
    contact_radius
        mm: the contact zone (module docstring) about the TCP and about the weld spots that a
        motion's ``exempt`` names.
    min_step
        mm: sets the sample budget of a motion (:data:`DEFAULT_MIN_STEP`).
    """

    def __init__(
        self,
        part: trimesh.Trimesh,
        tool: Tool,
        clearance: float,
        contact_radius: float,
        *,
        min_step: float = DEFAULT_MIN_STEP,
    ) -> None:
        if not (clearance >= 0 and contact_radius >= 0 and min_step > 0):
            raise ValueError("clearance and contact_radius >= 0 and min_step > 0 are needed")
        self.part = part
        self.tool = tool
        self.clearance = float(clearance)
        self.contact_radius = float(contact_radius)
        self.min_step = float(min_step)
        self.reach = tool.reach
        self._part = fcl.CollisionObject(
            bvh(np.asarray(part.vertices), np.asarray(part.faces)), fcl.Transform()
        )
        self._whole = fcl.CollisionObject(bvh(tool.vertices, tool.faces), fcl.Transform())
        v, f = tool.outside_zone(self.contact_radius)
        self._outside = fcl.CollisionObject(bvh(v, f), fcl.Transform())
        zv, zf = tool_zone(tool, self.contact_radius)
        self._zone = None if len(zf) == 0 else fcl.CollisionObject(bvh(zv, zf), fcl.Transform())
        self._cut: dict[tuple[float, ...], fcl.CollisionObject] = {}

    def _part_cut(self, spot: NDArray[np.float64]) -> fcl.CollisionObject:
        """A BVH of the part outside the zone about one weld spot (cached per spot)."""
        key = tuple(np.round(spot, 9).tolist())
        if key not in self._cut:
            v, f = outside_sphere(self.part.vertices, self.part.faces, spot, self.contact_radius)
            self._cut[key] = fcl.CollisionObject(bvh(v, f), fcl.Transform())
        return self._cut[key]

    def slack(self, p: ArrayLike, R: ArrayLike, exempt: ArrayLike | None = None) -> float:
        """mm by which the tool at TCP ``p (3,)``, ``R (3, 3)`` clears what it must (negative: it
        does not): the distance to the part less the clearance; with ``exempt (m, 3)`` weld spots,
        the least of (tool outside its zone to the whole part) less the clearance and (tool in
        its zone to the part outside the spots' zones), which need only not touch."""
        tf = fcl.Transform(np.asarray(R, dtype=np.float64), np.asarray(p, dtype=np.float64))
        req = fcl.DistanceRequest()
        ex = None if exempt is None else np.asarray(exempt, dtype=np.float64).reshape(-1, 3)
        if ex is None or len(ex) == 0:
            self._whole.setTransform(tf)
            d = float(fcl.distance(self._whole, self._part, req, fcl.DistanceResult()))
            return d - self.clearance
        self._outside.setTransform(tf)
        d = float(fcl.distance(self._outside, self._part, req, fcl.DistanceResult()))
        slack = d - self.clearance
        if self._zone is not None:
            # the part outside every zone is a subset of the part outside each one, so the
            # largest distance to those is a lower bound of the distance that counts
            self._zone.setTransform(tf)
            dz = max(
                float(fcl.distance(self._zone, self._part_cut(e), req, fcl.DistanceResult()))
                for e in ex
            )
            slack = min(slack, dz)
        return slack

    def state_ok(self, p: ArrayLike, q: ArrayLike, exempt: ArrayLike | None = None) -> bool:
        """Whether one pose (TCP ``p (3,)`` mm, ``q`` wxyz) clears (:meth:`slack` >= 0)."""
        return self.slack(p, quat_to_matrix(q), exempt) >= 0.0

    def check(
        self,
        p0: ArrayLike,
        q0: ArrayLike,
        p1: ArrayLike,
        q1: ArrayLike,
        exempt: ArrayLike | None = None,
        soft: tuple[bool, bool] = (True, True),
    ) -> SweepCheck:
        """Check the motion ``(p0, q0) -> (p1, q1)`` by conservative advancement (module
        docstring) on :meth:`slack`. ``exempt (m, 3)``: the weld spots whose zones apply.
        ``soft``: whether the advancement from the start (from the end) may take steps shorter
        than ``min_step`` over its first ``max(contact_radius, 10 min_step)`` mm of tool motion
        (a weld pose's slack may be small); elsewhere a slack below ``min_step`` blocks the
        motion at once (fail fast: OMPL asks about many motions)."""
        L = motion_bound(p0, q0, p1, q1, self.reach)
        budget = [max_samples(L, self.min_step)]
        smin = [math.inf]

        def slack_at(s: float) -> float:
            pos, rot = interpolate(p0, q0, p1, q1, [s])
            v = self.slack(pos[0], rot[0], exempt)
            budget[0] -= 1
            smin[0] = min(smin[0], v)
            return v

        # forward from the start and backward from the end, meeting half-way: the slack at a
        # weld pose may be small, and grows as the tool leaves it
        blocked = float("nan")
        for start, stop, sign, may in ((0.0, 0.5, 1.0, soft[0]), (1.0, 0.5, -1.0, soft[1])):
            s = start
            while True:
                v = slack_at(s)
                soft_here = may and abs(s - start) * L <= max(
                    self.contact_radius, 10 * self.min_step
                )
                short = v < self.min_step and not soft_here
                if v < 0 or (v == 0 and L > 0) or budget[0] < 0 or (short and L > 0):
                    blocked = s
                    break
                if L <= 0 or sign * (stop - s) <= 0:
                    break
                s = s + sign * min(v / L, sign * (stop - s))
            if not math.isnan(blocked):
                break
        n = max_samples(L, self.min_step) - budget[0]
        ok = math.isnan(blocked)
        return SweepCheck(ok, n, smin[0], blocked, L)


def max_samples(bound: float, min_step: float) -> int:
    """Samples one motion of bound ``bound`` mm may take: ``2 (bound / min_step + 1)``."""
    return 2 * (math.ceil(bound / min_step) + 1)


def exempt_for(*spots: Any) -> NDArray[np.float64] | None:
    """``(m, 3)`` from the spots given (``None`` entries dropped), ``None`` when there are none."""
    pts = [np.asarray(s, dtype=np.float64).reshape(3) for s in spots if s is not None]
    return np.array(pts) if pts else None
