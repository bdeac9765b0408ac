"""The FCL queries of the weld-pose search: candidate collisions, clearances and closest misses.

:class:`PoseSearch` holds the python-fcl objects of one search (never shared with the
independent re-check, :mod:`weldplan.tool.verify.poses`): the tool minus its contact zone as one
BVH moved by ``setTransform`` through all candidates, and the part: a BVH per weld of the
triangles whose bounding boxes come within the tool's reach of the spot (``crop=True``, the
default), or one BVH of the whole mesh built once (``crop=False``). Both give the same answers:
no triangle outside the reach can touch the tool. Measured on 20 welds of car2 (18,394 triangles,
one-off profiles at load 1-5 on 2 cores): a crop costs about 50-80 ms a weld to build,
but against the whole part a ``distance`` cost about 6x and a ``collide`` about 1.7x as much,
which outweighs it; ``weldplan bench tool --whole-part`` measures it again.

A closest miss (a weld with no free candidate) is the candidate whose deepest triangle-pair
penetration is least (ties: fewest tool triangles touching). Measuring that needs every contact
of a candidate, which cost about 4 ms a candidate on car2 (thousands of contacts turned into
Python objects). So the candidates are first ranked by a probe, ``collide`` with at most
:data:`MISS_PROBE_CONTACTS` contacts and no contact data (the fewer triangle pairs touch, the
closer to free), on at most :data:`MISS_PROBES` candidates spread evenly over the list (a cap of
8 makes a ``collide`` 2-3x as dear as the search's yes/no one, so the probe is not folded into
the search), and only
the :data:`MISS_SHORTLIST` best of them are measured fully. The miss is therefore the closest
among the shortlist, not necessarily among all candidates: a report of how and where the tool
hits, not an optimum.
"""

from __future__ import annotations

import logging
import weakref
from typing import Any

import fcl
import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.tool.model.tool import Tool, bvh
from weldplan.tool.poses.bound import PoseBound, ToolPieces
from weldplan.tool.poses.result import Miss
from weldplan.tool.verify.poses import triangle_crossings

log = logging.getLogger(__name__)

#: contacts asked of FCL per shortlisted candidate when measuring a closest miss
MISS_CONTACTS = 10_000
#: contact cap of the probe that ranks a missed weld's candidates
MISS_PROBE_CONTACTS = 8
#: the probe looks at up to this many candidates of a missed weld, evenly spread over its list
MISS_PROBES = 200
#: candidates of a missed weld measured fully (the probe's best)
MISS_SHORTLIST = 4
#: candidates whose clearance a search measures by the whole tool before it builds the pieces
#: of :class:`~weldplan.tool.poses.PoseBound` (each saves about 1 ms of the 0.4 s they
#: cost on the shared gun; the demo judges about 1,700)
PIECES_AFTER = 256
#: welds within this distance (mm) of the spot a crop was made for share that crop (made that
#: much larger), so that a line of spots 40-60 mm apart builds a BVH every few welds
CROP_SHARE_MM = 100.0


def probe_positions(n: int) -> NDArray[np.int64]:
    """The positions among ``n`` candidates that the closest-miss probe looks at: up to
    :data:`MISS_PROBES`, evenly spread."""
    return np.unique(np.linspace(0, n - 1, min(n, MISS_PROBES)).astype(np.int64))


def _memo(
    tool: Tool, part: trimesh.Trimesh, radius: float, clearance: float, crop: bool
) -> dict[str, Any]:
    """The collide and clearance answers of the searches of ``part`` with ``tool`` (cached on
    the tool, for the one part it was last searched against): a station's poses are searched
    twice (without the robot's test for the base search, then with it), over the same
    candidates. Keyed by the TCP position and rotation bytes (and the contact cap): the same
    query, the same FCL answer."""
    key = ("pose_memo", float(radius), float(clearance), bool(crop), tool.tip_cone)
    memo = tool._cache.get(key)
    if memo is None or memo["part"]() is not part:
        memo = tool._cache[key] = {"part": weakref.ref(part), "touch": {}, "clear": {}}
    return memo


class PoseSearch:
    """The cached FCL objects of one pose search.

    Parameters
    ----------
    part
        The part (mm).
    tool
        The tool (mm, TCP frame); its contact zone is :meth:`~weldplan.tool.model.Tool.in_zone`.
    radius
        mm: the contact-zone radius.
    clearance
        mm: the least distance between the tool outside the zone and the part.
    crop
        Build a BVH per weld of the part near it instead of one of the whole part (module
        docstring).
    """

    def __init__(
        self,
        part: trimesh.Trimesh,
        tool: Tool,
        radius: float,
        clearance: float,
        *,
        crop: bool = True,
    ) -> None:
        self.part = part
        self.tool = tool
        self.radius = float(radius)
        self.clearance = clearance
        self.crop = crop
        model, self.triangles = tool.fcl_model(radius)
        self.tool_obj = fcl.CollisionObject(model, fcl.Transform())
        tri = np.asarray(part.triangles)
        self.lo, self.hi = tri.min(axis=1), tri.max(axis=1)
        self.reach = tool.reach + clearance
        self._whole: fcl.CollisionObject | None = None
        self._last: tuple[NDArray, fcl.CollisionObject | None, NDArray[np.int64]] | None = None
        #: crops built so far (``crop=True``)
        self.crops_built = 0
        self._bound: PoseBound | None = None
        #: candidates whose clearance :meth:`clearances` judged, those the sphere bound alone
        #: showed free, the FCL distance queries of tool pieces it asked, and the collide and
        #: clearance answers found in the memo of an earlier search (:func:`_memo`)
        self.bound_counts = {"judged": 0, "bound_free": 0, "piece_queries": 0, "memo": 0}
        self._memo = _memo(tool, part, radius, clearance, crop)

    def near_faces(self, p: NDArray, margin: float = 0.0) -> NDArray[np.int64]:
        """``(k,)``: indices of the part's triangles whose bounding boxes come within the tool's
        reach (plus ``margin`` mm) of ``p`` (no other triangle can touch the tool with its TCP
        within ``margin`` of ``p``)."""
        gap = np.maximum(self.lo - p, 0) + np.maximum(p - self.hi, 0)
        return np.flatnonzero(np.einsum("ij,ij->i", gap, gap) <= (self.reach + margin) ** 2)

    def part_near(self, p: NDArray) -> tuple[fcl.CollisionObject | None, NDArray[np.int64]]:
        """The part object to check the tool against with its TCP at ``p``, and the part
        triangle index of each of its BVH's triangles. ``None`` when no triangle is in reach.

        With ``crop``, the last crop is reused while ``p`` lies within :data:`CROP_SHARE_MM` of
        the spot it was made for (it holds every triangle within the reach plus that margin).
        """
        if not self.crop:
            if len(self.near_faces(p)) == 0:
                return None, np.zeros(0, dtype=np.int64)
            if self._whole is None:
                faces = np.asarray(self.part.faces)
                self._whole = fcl.CollisionObject(bvh(self.part.vertices, faces), fcl.Transform())
            return self._whole, np.arange(len(self.part.faces))
        if self._last is not None and np.linalg.norm(p - self._last[0]) <= CROP_SHARE_MM:
            return self._last[1], self._last[2]
        near = self.near_faces(p, CROP_SHARE_MM)
        obj = None
        if len(near):
            faces = np.asarray(self.part.faces)[near]
            obj = fcl.CollisionObject(bvh(self.part.vertices, faces), fcl.Transform())
            self.crops_built += 1
        self._last = (np.asarray(p, dtype=np.float64).copy(), obj, near)
        return obj, near

    def collides(self, part_obj: fcl.CollisionObject | None, p: NDArray, Rs: NDArray) -> NDArray:
        """``(c,) bool``: whether the tool outside the zone collides at each rotation ``(c, 3, 3)``
        with the TCP at ``p`` (one python-fcl ``collide`` each, the tool's BVH moved)."""
        return self._touching(part_obj, p, Rs, 1) > 0

    def touching(
        self,
        part_obj: fcl.CollisionObject | None,
        p: NDArray,
        Rs: NDArray,
        probe: NDArray[np.bool_],
    ) -> NDArray[np.int64]:
        """``(c,) int``: :meth:`collides` and the closest-miss probe at once. Where ``probe (c,)``
        is set, the triangle pairs touching counted up to :data:`MISS_PROBE_CONTACTS` (what
        :meth:`miss` ranks by, so it need not ask again: pass them as its ``known``); elsewhere
        1 where the tool collides, else 0. On car2 175 of 200 welds have no free candidate, and
        a probe folded into the collision query spares one yes/no query per probe."""
        out = np.zeros(len(Rs), dtype=np.int64)
        probe = np.asarray(probe, dtype=bool)
        out[~probe] = self._touching(part_obj, p, Rs[~probe], 1)
        out[probe] = self._touching(part_obj, p, Rs[probe], MISS_PROBE_CONTACTS)
        return out

    def _touching(
        self, part_obj: fcl.CollisionObject | None, p: NDArray, Rs: NDArray, cap: int
    ) -> NDArray[np.int64]:
        """``(c,) int``: triangle pairs touching at each rotation, counted up to ``cap``."""
        out = np.zeros(len(Rs), dtype=np.int64)
        if part_obj is None:
            return out
        req = fcl.CollisionRequest(num_max_contacts=cap, enable_contact=False)
        memo = self._memo["touch"]
        at = np.ascontiguousarray(p, dtype=np.float64).tobytes() + bytes([cap])
        for k, R in enumerate(Rs):
            key = at + np.ascontiguousarray(R, dtype=np.float64).tobytes()
            hit = memo.get(key)
            if hit is None:
                self.tool_obj.setTransform(fcl.Transform(R, p))
                hit = memo[key] = fcl.collide(self.tool_obj, part_obj, req, fcl.CollisionResult())
            else:
                self.bound_counts["memo"] += 1
            out[k] = hit
        return out

    def distance(self, part_obj: fcl.CollisionObject | None, p: NDArray, R: NDArray) -> float:
        """mm: FCL distance from the tool outside the zone to the part (``inf``: none near)."""
        if part_obj is None:
            return float("inf")
        self.tool_obj.setTransform(fcl.Transform(R, p))
        return float(
            fcl.distance(self.tool_obj, part_obj, fcl.DistanceRequest(), fcl.DistanceResult())
        )

    def clearances(
        self,
        part_objs: list[fcl.CollisionObject | None],
        P: NDArray,
        Rs: NDArray,
        *,
        first_free: bool = False,
    ) -> NDArray[np.float64]:
        """``(c,)`` mm: whether the tool outside the zone keeps the clearance with the TCP at
        ``P (c, 3)`` and rotations ``Rs (c, 3, 3)``, checked against ``part_objs`` (``c`` of
        :meth:`part_near`'s objects), for candidates that do not collide: at least
        :attr:`clearance` exactly where it does, but a bound, not the distance
        (:class:`~weldplan.tool.poses.PoseBound`: sphere bounds, FCL on the tool's pieces
        that they do not clear). ``first_free``: up to the first that keeps it, NaN after.

        Until the tool's pieces are built, the first :data:`PIECES_AFTER` candidates a search
        judges are measured by FCL's distance of the whole tool (exact): the pieces cost about
        0.4 s to build for the shared gun, more than a station with few judgements spends on
        them (car2_50: 32)."""
        if self.clearance <= 0:
            return np.full(len(Rs), np.inf)
        memo = self._memo["clear"]
        keys = [
            np.ascontiguousarray(p, dtype=np.float64).tobytes()
            + np.ascontiguousarray(R, dtype=np.float64).tobytes()
            for p, R in zip(P, Rs, strict=True)
        ]
        known = np.array([memo.get(k, np.nan) for k in keys])
        free = np.flatnonzero(known >= self.clearance)
        upto = int(free[0]) + 1 if first_free and len(free) else len(keys)
        if not np.isnan(known[:upto]).any():  # an earlier search judged them all
            self.bound_counts["memo"] += upto
            known[upto:] = np.nan
            return known
        out = self._judge(part_objs, P, Rs, first_free)
        for k, v in zip(keys, out, strict=True):
            if not np.isnan(v):
                memo[k] = float(v)
        return out

    def _judge(
        self,
        part_objs: list[fcl.CollisionObject | None],
        P: NDArray,
        Rs: NDArray,
        first_free: bool,
    ) -> NDArray[np.float64]:
        """:meth:`clearances` without the memo."""
        built = ToolPieces.cached(self.tool, self.radius)
        if self._bound is None and self.bound_counts["judged"] < PIECES_AFTER and not built:
            out = np.full(len(Rs), np.nan)
            for a, (obj, p, R) in enumerate(zip(part_objs, P, Rs, strict=True)):
                out[a] = self.distance(obj, p, R)
                if first_free and out[a] >= self.clearance:
                    break
            self.bound_counts["judged"] += int(np.sum(~np.isnan(out)))
            return out
        if self._bound is None:
            self._bound = PoseBound(self.part, self.tool, self.radius, self.clearance)
        out = self._bound.classify(part_objs, P, Rs, first_free=first_free)
        self.bound_counts["judged"] += int(np.sum(~np.isnan(out.value)))
        self.bound_counts["piece_queries"] += out.fcl_queries
        self.bound_counts["bound_free"] += out.bound_free
        return out.value

    def miss(
        self,
        part_obj: fcl.CollisionObject,
        index: NDArray[np.int64],
        p: NDArray,
        Rs: NDArray,
        dist: NDArray,
        params: NDArray,
        known: NDArray[np.int64] | None = None,
    ) -> Miss:
        """The closest miss among candidates none of which is free (module docstring).

        ``index`` maps the part object's triangles to the part's (:meth:`part_near`); ``dist
        (c,)`` holds each candidate's distance (0 where it collides); ``params (c, 4)`` each
        candidate's spin, tilt, azimuth (deg) and whether it is turned over (1.0); ``known
        (c,)`` the probe's counts already taken (:meth:`touching`; -1 where not), not asked again.
        """
        if np.any(dist > 0):  # clearance shortfalls: the largest distance
            k = int(np.argmax(dist))
            self.tool_obj.setTransform(fcl.Transform(Rs[k], p))
            res = fcl.DistanceResult()
            req_d = fcl.DistanceRequest(enable_nearest_points=True)
            d = fcl.distance(self.tool_obj, part_obj, req_d, res)
            pt = (np.asarray(res.nearest_points[0]) - p) @ Rs[k]  # world -> TCP frame
            return _miss(params[k], float(d), 0.0, 0, pt, self.tool)
        probed = probe_positions(len(Rs))
        touching = np.full(len(probed), -1) if known is None else np.asarray(known)[probed]
        ask = touching < 0
        touching[ask] = self._touching(part_obj, p, Rs[probed[ask]], MISS_PROBE_CONTACTS)
        shortlist = probed[np.argsort(touching, kind="stable")[:MISS_SHORTLIST]]
        verts = np.asarray(self.part.vertices)
        faces = np.asarray(self.part.faces)
        best: tuple[float, int, int, NDArray] | None = None
        req = fcl.CollisionRequest(num_max_contacts=MISS_CONTACTS, enable_contact=True)
        for k in shortlist:
            R = Rs[k]
            self.tool_obj.setTransform(fcl.Transform(R, p))
            res = fcl.CollisionResult()
            fcl.collide(self.tool_obj, part_obj, req, res)
            if not res.contacts:
                continue
            depth = np.array([c.penetration_depth for c in res.contacts])
            deepest = int(np.argmax(depth))
            n_tri = len({c.b1 for c in res.contacts})
            key = (float(depth[deepest]), n_tri)
            if best is None or key < best[:2]:
                c = res.contacts[deepest]
                # where the hitting tool triangle crosses the part's triangle (TCP frame)
                other = (verts[faces[index[c.b2]]] - p) @ R
                pts, ok = triangle_crossings(self.triangles[c.b1][None], other[None])
                pt = pts[0, ok[0]].mean(axis=0) if ok.any() else self.triangles[c.b1].mean(axis=0)
                best = (key[0], key[1], int(k), pt)
        if best is None:
            raise RuntimeError("a missed weld's candidates reported no contacts (a bug)")
        pen, n_tri, k, pt = best
        return _miss(params[k], 0.0, pen, n_tri, pt, self.tool)


def _miss(par: NDArray, d: float, pen: float, n: int, pt: NDArray, tool: Tool) -> Miss:
    return Miss(
        spin=float(par[0]),
        tilt=float(par[1]),
        azimuth=float(par[2]),
        distance=d,
        penetration=pen,
        contacts=n,
        tool_point=tuple(float(v) for v in pt),  # type: ignore[arg-type]
        region=tool.region(pt),
        flipped=bool(par[3]),
    )
