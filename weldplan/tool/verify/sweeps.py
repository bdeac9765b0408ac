"""The independent re-check of the tool's transitions: fresh FCL models, uniform samples, own bound.

The transition planner (:mod:`weldplan.tool.transitions.plan`) checks motions by conservative
advancement with the FCL models of its :class:`~weldplan.tool.transitions.SweepChecker`. This module
shares none of them: it rebuilds python-fcl models of the whole part, of the tool outside its
contact zone and of the tool inside it (from the tool's raw mesh, here), and of the part outside
each weld's zone; it interpolates each motion with :class:`scipy.spatial.transform.Slerp`
(the planner uses a rotation vector); and it tests the motion differently:

* samples are **uniform** in the motion parameter, spaced so that no tool point moves more than
  ``spacing`` mm between two of them (the bound ``L = |dp| + theta r``, ``r`` the largest distance
  of a tool vertex from the TCP, recomputed here);
* between consecutive samples ``k, k+1`` (``h`` apart) the slack (distance less clearance, with
  the contact-zone rule of :mod:`weldplan.tool.transitions.sweep`) cannot fall below
  ``(slack_k + slack_{k+1} - L h) / 2``: the motion passes where that is ``>= 0`` on every
  interval, and an interval where it is not is bisected (at most :data:`MAX_DEPTH` times) before
  the motion is declared failed.

The first grid is coarse (:data:`DEFAULT_SPACING`, 32 mm) and the bisections go deep
(:data:`MAX_DEPTH`, 11): the finest interval is the one a 4 mm grid bisected 8 times gives
(1/64 mm of tool motion), but only where the bound asks for it. Away from the part one sample
in 32 mm of tool motion proves the interval; near a weld, where the slack is small, the
bisections reach the fine samples a dense grid would have taken. The guarantee is the bound's,
whatever the grid: a passed motion keeps the slack between every two samples.

It also checks that the path is the route's: each transition starts and ends at the weld poses
the route reports (spot and quaternion), the transitions chain in the reported order, and the
order visits exactly the welds with a pose.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation, Slerp

from weldplan.geometry.checker import CheckVerdict
from weldplan.tool.model.tool import Tool, bvh
from weldplan.tool.poses.result import WeldPoses
from weldplan.tool.transitions.result import ToolPath
from weldplan.tool.transitions.sweep import outside_sphere

log = logging.getLogger(__name__)

#: mm: default largest tool-point motion between two samples of a motion's first, uniform grid
#: (on the demo station's 14 transitions: 1,079 samples against 1,879 with a 4 mm grid bisected
#: at most 8 times, the same finest interval)
DEFAULT_SPACING = 32.0
#: bisections of an interval the bound cannot clear before the motion fails (an interval of
#: ``spacing`` mm of tool motion halved this many times: 32 mm / 2^11 = 1/64 mm)
MAX_DEPTH = 11
#: mm: slack on positions and the clearance for floating-point round-off
TOLERANCE_MM = 1e-6


@dataclass(frozen=True)
class SweepsVerification:
    """Outcome of :func:`verify_sweeps`: ``ok`` when every free transition passed.

    ``blocked`` lists the transitions the planner reported blocked (not a failure of the check:
    a partial tool path); ``failures`` the transitions that failed, with why.
    """

    ok: bool
    checked: int
    samples: int
    blocked: tuple[str, ...] = ()
    failures: tuple[tuple[str, str], ...] = ()
    #: mm: the least slack sampled plus the clearance, a lower bound of the least distance of
    #: the tool to what it must keep off (the contact-zone rule of
    #: :mod:`weldplan.tool.transitions.sweep`; ``nan``: nothing sampled)
    min_clearance: float = math.nan

    @property
    def verdict(self) -> CheckVerdict:
        """This check as a :class:`~weldplan.geometry.checker.CheckVerdict` (places:
        transitions ``from->to``; left out: the transitions the planner reported blocked)."""
        return CheckVerdict.of(
            "tool transitions", self.checked, self.failures, ok=self.ok,
            min_clearance=self.min_clearance, left_out=self.blocked,
        )  # fmt: skip

    def describe(self, limit: int = 10) -> str:
        if not self.ok:
            shown = "; ".join(f"{k}: {r}" for k, r in self.failures[:limit])
            more = len(self.failures) - limit
            return f"{len(self.failures)} transition failure(s): {shown}" + (
                f"; ... {more} more" if more > 0 else ""
            )
        text = (
            f"{self.checked} transitions of the swept tool re-checked ({self.samples} FCL "
            f"distance samples, fresh models)"
        )
        if self.blocked:
            text += f"; blocked (reported by the planner): {', '.join(self.blocked)}"
        return text


class _Sweeps:
    """Fresh FCL models for the re-check (never shared with the planner).

    Two exact reductions keep the distance queries small, derived here on their own:

    * **crop per transition** (:meth:`crop`): a tool point lies within ``reach`` of the TCP and
      the TCP stays in the bounding box of the transition's waypoints (straight segments), so a
      part triangle whose bounding box is farther than ``reach + clearance + 1`` mm from that
      box never comes within the clearance of the tool: the distances that matter are the same
      against the crop;
    * **the zone's part per spot** (:meth:`_cut`): the zone's distance counts only where it is
      below the outside's slack. Where the TCP is at least ``zone_reach + radius`` from a spot,
      the zone cannot enter that spot's sphere, so its distance to the part outside the sphere
      is at least its distance to the (cropped) part. Nearer, every zone point lies within
      ``2 zone_reach + radius`` of the spot, so the part beyond ``2 zone_reach + radius + CAP``
      of it is at least ``CAP`` away: the distance to the part near the spot, outside its
      sphere, capped at ``CAP``, is a lower bound.
    """

    #: mm: the cap of the zone distance near a spot (above)
    CAP = 25.0

    def __init__(self, part: trimesh.Trimesh, tool: Tool, clearance: float, radius: float):
        self.part = part
        self.clearance = clearance
        self.radius = radius
        V = np.asarray(tool.vertices, dtype=np.float64)
        F = np.asarray(tool.faces, dtype=np.int64)
        self.reach = float(np.sqrt((V**2).sum(axis=1)).max())
        ov, of = outside_sphere(V, F, np.zeros(3), radius)
        self.outside = fcl.CollisionObject(bvh(ov, of), fcl.Transform())
        # the tool inside its zone: every triangle with a vertex within radius + its longest edge
        tri = V[F]
        edge = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
        zone = np.linalg.norm(tri, axis=2).min(axis=1) <= radius + edge
        self.zone = fcl.CollisionObject(bvh(V, F[zone]), fcl.Transform()) if zone.any() else None
        used = np.unique(F[zone])
        self.zone_reach = float(np.linalg.norm(V[used], axis=1).max()) if zone.any() else 0.0
        PT = np.asarray(part.triangles)
        self.lo, self.hi = PT.min(axis=1), PT.max(axis=1)
        self.part_obj: fcl.CollisionObject | None = None
        self.cuts: dict[tuple[float, ...], fcl.CollisionObject | None] = {}
        self.samples = 0
        #: mm: the least slack sampled
        self.least = math.inf

    def _near(self, lo: NDArray, hi: NDArray, pad: float) -> NDArray[np.int64]:
        """The part's faces whose bounding boxes come within ``pad`` of the box ``[lo, hi]``."""
        gap = np.maximum(self.lo - hi, 0) + np.maximum(lo - self.hi, 0)
        return np.asarray(self.part.faces)[np.einsum("ij,ij->i", gap, gap) <= pad * pad]

    def crop(self, positions: NDArray) -> None:
        """Check the next transition (its TCP waypoints ``(k, 3)``) against the part near it."""
        f = self._near(
            positions.min(axis=0), positions.max(axis=0), self.reach + self.clearance + 1
        )
        self.part_obj = None if len(f) == 0 else fcl.CollisionObject(
            bvh(self.part.vertices, f), fcl.Transform())  # fmt: skip

    def _cut(self, spot: NDArray) -> fcl.CollisionObject | None:
        key = tuple(spot.tolist())
        if key not in self.cuts:
            f = self._near(spot, spot, 2 * self.zone_reach + self.radius + self.CAP)
            v, f = outside_sphere(self.part.vertices, f, spot, self.radius, bisect=True)
            self.cuts[key] = None if len(f) == 0 else fcl.CollisionObject(
                bvh(v, f), fcl.Transform())  # fmt: skip
        return self.cuts[key]

    def slack(self, R: NDArray, p: NDArray, spots: NDArray) -> float:
        s = self._slack(R, p, spots)
        self.least = min(self.least, s)
        return s

    def _slack(self, R: NDArray, p: NDArray, spots: NDArray) -> float:
        self.samples += 1
        if self.part_obj is None:
            return math.inf
        tf = fcl.Transform(R, p)
        self.outside.setTransform(tf)
        d = fcl.distance(self.outside, self.part_obj, fcl.DistanceRequest(), fcl.DistanceResult())
        s = float(d) - self.clearance
        if self.zone is None:
            return s
        self.zone.setTransform(tf)
        dz = float(fcl.distance(self.zone, self.part_obj, fcl.DistanceRequest(),
                                fcl.DistanceResult()))  # fmt: skip
        if dz >= s:
            return s
        best = dz
        for e in spots:
            if float(np.linalg.norm(p - e)) >= self.zone_reach + self.radius:
                continue
            cut = self._cut(e)
            req, res = fcl.DistanceRequest(), fcl.DistanceResult()
            de = math.inf if cut is None else float(fcl.distance(self.zone, cut, req, res))
            best = max(best, min(de, self.CAP))
        return min(s, best)

    def motion(self, p0, q0, p1, q1, spots: NDArray, spacing: float) -> str:
        """'' when the motion keeps the slack >= 0 throughout, else why not."""
        key = Rotation.from_quat([np.roll(q0, -1), np.roll(q1, -1)])
        slerp = Slerp([0.0, 1.0], key)
        theta = float(key[0].inv().__mul__(key[1]).magnitude())
        L = float(np.linalg.norm(p1 - p0)) + theta * self.reach
        n = max(1, math.ceil(L / spacing))

        def at(s: float) -> float:
            R = slerp([s]).as_matrix()[0]
            return self.slack(R, p0 + s * (p1 - p0), spots)

        grid = np.linspace(0.0, 1.0, n + 1)
        # the grid's orientations in one Slerp call (elementwise: those of at(s) one by one)
        rots = slerp(grid).as_matrix()
        vals = [self.slack(R, p0 + s * (p1 - p0), spots) for s, R in zip(grid, rots, strict=True)]
        if min(vals) < -TOLERANCE_MM:
            k = int(np.argmin(vals))
            return f"at {100 * grid[k]:.0f} % of a motion the tool lacks {-vals[k]:.2f} mm"
        stack = [(grid[k], grid[k + 1], vals[k], vals[k + 1], 0) for k in range(n)]
        while stack:
            a, b, fa, fb, depth = stack.pop()
            if (fa + fb - L * (b - a)) / 2 >= -TOLERANCE_MM:
                continue
            if depth >= MAX_DEPTH:
                return (
                    f"between {100 * a:.1f} and {100 * b:.1f} % of a motion the clearance "
                    f"cannot be shown (bound {(fa + fb - L * (b - a)) / 2:.2f} mm)"
                )
            m = (a + b) / 2
            fm = at(m)
            if fm < -TOLERANCE_MM:
                return f"at {100 * m:.1f} % of a motion the tool lacks {-fm:.2f} mm"
            stack += [(a, m, fa, fm, depth + 1), (m, b, fm, fb, depth + 1)]
        return ""


def _end_mismatch(t: Any, poses: WeldPoses) -> str:
    for end, wid, k in (("start", t.from_id, 0), ("end", t.to_id, -1)):
        wp = poses[wid]
        if wp.quaternion is None:
            return f"{end} weld {wid} has no pose"
        if np.max(np.abs(t.positions[k] - np.asarray(wp.position))) > 1e-6:
            return f"{end} is not at weld {wid}'s spot"
        dot = abs(float(np.dot(t.quaternions[k], np.asarray(wp.quaternion))))
        if dot < 1.0 - 1e-9:
            return f"{end} orientation is not weld {wid}'s pose"
    return ""


def _check_free(
    transitions: list[Any],
    poses: WeldPoses,
    part: trimesh.Trimesh,
    tool: Tool,
    spacing: float,
) -> tuple[list[tuple[str, str]], int, float]:
    """The failures among the free ``transitions`` (name, why), the samples taken and the least
    slack sampled plus the clearance (mm, ``inf``: none sampled), with
    fresh models built here (one process's share of :func:`verify_sweeps`)."""
    clearance = float(poses.settings["clearance"])
    radius = float(poses.settings["contact_radius"])
    sw = _Sweeps(part, tool, clearance, radius)
    failures: list[tuple[str, str]] = []
    for t in transitions:
        why = _end_mismatch(t, poses)
        Q = t.quaternions
        if not why and np.any(np.abs(np.linalg.norm(Q, axis=1) - 1.0) > 1e-6):
            why = "a quaternion is not a unit quaternion"
        if not why:
            spots = np.array([poses[t.from_id].position, poses[t.to_id].position], dtype=float)
            sw.crop(np.asarray(t.positions, dtype=np.float64))
            for k in range(len(t.positions) - 1):
                why = sw.motion(t.positions[k], Q[k], t.positions[k + 1], Q[k + 1], spots, spacing)
                if why:
                    why = f"motion {k} ({t.kinds[k]}): {why}"
                    break
        if why:
            failures.append((f"{t.from_id}->{t.to_id}", why))
    return failures, sw.samples, sw.least + clearance


def verify_sweeps(
    path: ToolPath,
    poses: WeldPoses,
    part: trimesh.Trimesh,
    tool: Tool,
    *,
    spacing: float = DEFAULT_SPACING,
) -> SweepsVerification:
    """Re-check every free transition of ``path`` for the swept ``tool`` (module docstring).

    The clearance and the contact radius are the poses' settings (what the pose search and the
    planner used).
    """
    failures: list[tuple[str, str]] = []
    ok_ids = sorted(p.id for p in poses.poses if p.ok)
    if sorted(path.order) != ok_ids:
        failures.append(("order", "the tool path does not visit exactly the welds with a pose"))
    free = [t for t in path.transitions if t.free]
    blocked = [f"{t.from_id}->{t.to_id}" for t in path.transitions if not t.free]
    fails, samples, least = _check_free(free, poses, part, tool, spacing)
    failures += fails
    return SweepsVerification(
        ok=not failures,
        checked=len(free),
        samples=samples,
        blocked=tuple(blocked),
        failures=tuple(failures),
        min_clearance=least if math.isfinite(least) else math.nan,
    )
