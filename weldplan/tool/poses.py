"""A collision-free tool pose for every weld: approach axis, spin, tilt, least rotation en route.

For each weld the tool's TCP sits on the weld spot with its +z axis along the approach axis (the
joints CSV's direction reversed: the CSV points from the joint towards the torch; without one,
the part's surface normal at the closest point, on the free side). Candidates spin about that
axis (every ``spin_step`` degrees) and tilt off it inside a cone (rings every ``tilt_step`` up
to ``cone`` degrees, ``azimuths`` directions per ring), :mod:`weldplan.tool.orient`.

A candidate is free when the tool **minus its part inside the contact zone** (the sphere of
``contact_radius`` mm about the TCP, i.e. about the weld spot, where the electrodes or the wire
touch the sheet; :meth:`~weldplan.tool.model.Tool.outside_zone`) does not collide with the part
and is at least ``clearance`` mm from it (python-fcl ``collide``, then ``distance`` for those
that do not collide). The part is cropped to the triangles whose bounding boxes come within the
tool's reach of the spot (exact: no other triangle can touch the tool) and built into one BVH per
weld; the tool's BVH is built once and moved by ``setTransform`` through all candidates.

Among the free candidates, the pose of each weld is chosen by dynamic programming along the route
order so that the summed rotation between consecutive welds is least
(:func:`~weldplan.tool.orient.least_rotation_choice`); welds without a free pose are skipped in
that chain and reported with their closest miss. Every chosen pose is re-checked by
:class:`~weldplan.tool.verify_poses.PoseChecker` (fresh FCL models of the whole part and tool)
before it is reported ok; a pose that fails is dropped from its weld's candidates and the choice
is made again.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError
from weldplan.tool.model import Tool, bvh
from weldplan.tool.orient import candidate_rotations, least_rotation_choice, local_candidates
from weldplan.tool.result import NO_FREE_POSE, OK, Miss, WeldPose, WeldPoses, quat_wxyz
from weldplan.tool.verify_poses import PoseChecker, triangle_crossings

log = logging.getLogger(__name__)

#: default half-angle (deg) of the tilt cone about the approach axis (issue 16)
DEFAULT_CONE = 15.0
#: default tilt ring spacing (deg)
DEFAULT_TILT_STEP = 7.5
#: default spin spacing about the approach axis (deg)
DEFAULT_SPIN_STEP = 15.0
#: default tilt directions per ring
DEFAULT_AZIMUTHS = 8
#: default contact-zone radius about the weld spot (mm, issue 16)
DEFAULT_CONTACT_RADIUS = 20.0
#: default clearance (mm) when neither the call nor a cell gives one: the cell's torch-tip default
DEFAULT_CLEARANCE = 5.0
#: contacts asked of FCL per candidate when measuring a closest miss
_MISS_CONTACTS = 10_000
#: rounds of the lazy choice before giving up (each round settles a weld or rejects a pose)
_MAX_ROUNDS = 1000


@dataclass(frozen=True)
class _Welds:
    ids: tuple[str, ...]
    xyz: NDArray[np.float64]
    directions: NDArray[np.float64] | None
    free_points: NDArray[np.float64] | None


def _welds(route_or_joints: Any, cell: Any) -> _Welds:
    """Weld ids, spots and directions in visiting order from a Route, Joints or a Cell."""
    src = route_or_joints if route_or_joints is not None else cell
    if src is None:
        raise ValueError("give the welds: a Route, Joints or a Cell")
    if hasattr(src, "joints") and hasattr(src, "part"):  # a Cell: its joints in file order
        virtual = np.asarray(src.virtual_xyz)
        src = src.joints
    else:
        virtual = None if cell is None else np.asarray(cell.virtual_xyz)
    if hasattr(src, "order") and hasattr(src, "joint_xyz"):  # a Route
        ids = tuple(src.joint_ids)
        idx = [ids.index(i) for i in src.order]
        xyz = np.asarray(src.joint_xyz)[idx]
        d = None if src.directions is None else np.asarray(src.directions)[idx]
        fp = None
        if src.virtual_xyz is not None:
            fp = np.asarray(src.virtual_xyz)[idx]
        elif virtual is not None:
            fp = virtual[idx]
        return _Welds(tuple(src.order), xyz, d, fp)
    ids = tuple(src.ids)
    d = None if src.directions is None else np.asarray(src.directions)
    return _Welds(ids, np.asarray(src.xyz), d, virtual)


def surface_approach(
    part: trimesh.Trimesh, points: ArrayLike, free_points: ArrayLike | None = None
) -> NDArray[np.float64]:
    """``(n, 3)`` unit approach axes (into the part) from the part's closest-point normals.

    The sign puts the tool on the free side: towards ``free_points (n, 3)`` when given (a cell's
    virtual joints, free voxel centres next to each spot), else on the side whose ray from the
    spot along the normal runs farther before it meets the part (trimesh ray casts).
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    _, _, tri = trimesh.proximity.closest_point(part, P)
    n = np.asarray(part.face_normals)[tri]
    if free_points is not None:
        sign = np.sign(np.sum((np.asarray(free_points).reshape(-1, 3) - P) * n, axis=1))
        sign[sign == 0] = 1.0
    else:
        eps = 1e-3
        free = []
        for s in (1.0, -1.0):
            origins = P + s * eps * n
            locs, ray_idx, _ = part.ray.intersects_location(origins, s * n, multiple_hits=False)
            far = np.full(len(P), np.inf)
            if len(ray_idx):
                far[ray_idx] = np.linalg.norm(locs - origins[ray_idx], axis=1)
            free.append(far)
        sign = np.where(free[0] >= free[1], 1.0, -1.0)
    # the normal points to the free (torch) side; the tool axis points into the part
    return -(n * sign[:, None])


class _Search:
    """The cached FCL objects of one pose search (never shared with the re-check)."""

    def __init__(self, part: trimesh.Trimesh, tool: Tool, radius: float, clearance: float) -> None:
        self.part = part
        self.tool = tool
        self.clearance = clearance
        model, self.triangles = tool.fcl_model(radius)
        self.tool_obj = fcl.CollisionObject(model, fcl.Transform())
        tri = np.asarray(part.triangles)
        self.lo, self.hi = tri.min(axis=1), tri.max(axis=1)
        self.reach = tool.reach + clearance

    def near_faces(self, p: NDArray) -> NDArray[np.int64]:
        """``(k, 3)``: the part's triangles whose bounding boxes come within the tool's reach of
        ``p`` (no other triangle can touch the tool with its TCP at ``p``)."""
        gap = np.maximum(self.lo - p, 0) + np.maximum(p - self.hi, 0)
        near = np.flatnonzero(np.einsum("ij,ij->i", gap, gap) <= self.reach**2)
        return np.asarray(self.part.faces)[near]

    def part_near(self, p: NDArray) -> fcl.CollisionObject | None:
        """A BVH of :meth:`near_faces`, or ``None`` when there are none."""
        faces = self.near_faces(p)
        if len(faces) == 0:
            return None
        return fcl.CollisionObject(bvh(self.part.vertices, faces), fcl.Transform())

    def collides(self, part_obj: fcl.CollisionObject | None, p: NDArray, Rs: NDArray) -> NDArray:
        """``(c,) bool``: whether the tool outside the zone collides at each rotation ``(c, 3, 3)``
        with the TCP at ``p`` (one python-fcl ``collide`` each, the tool's BVH moved)."""
        out = np.zeros(len(Rs), dtype=bool)
        if part_obj is None:
            return out
        req = fcl.CollisionRequest()
        for k, R in enumerate(Rs):
            self.tool_obj.setTransform(fcl.Transform(R, p))
            out[k] = fcl.collide(self.tool_obj, part_obj, req, fcl.CollisionResult()) > 0
        return out

    def distance(self, part_obj: fcl.CollisionObject | None, p: NDArray, R: NDArray) -> float:
        """mm: FCL distance from the tool outside the zone to the part (``inf``: none near)."""
        if part_obj is None:
            return float("inf")
        self.tool_obj.setTransform(fcl.Transform(R, p))
        return float(
            fcl.distance(self.tool_obj, part_obj, fcl.DistanceRequest(), fcl.DistanceResult())
        )

    def miss(
        self, part_obj: fcl.CollisionObject, p: NDArray, Rs: NDArray, dist: NDArray, params: NDArray
    ) -> Miss:
        """The closest miss among candidates none of which is free."""
        if np.any(dist > 0):  # clearance shortfalls: the largest distance
            k = int(np.argmax(dist))
            self.tool_obj.setTransform(fcl.Transform(Rs[k], p))
            res = fcl.DistanceResult()
            req_d = fcl.DistanceRequest(enable_nearest_points=True)
            d = fcl.distance(self.tool_obj, part_obj, req_d, res)
            pt = (np.asarray(res.nearest_points[0]) - p) @ Rs[k]  # world -> TCP frame
            return _miss(params[k], float(d), 0.0, 0, pt, self.tool)
        part_tri = np.asarray(self.part.vertices)[self.near_faces(p)]
        best: tuple[float, int, int, NDArray] | None = None
        req = fcl.CollisionRequest(num_max_contacts=_MISS_CONTACTS, enable_contact=True)
        for k, R in enumerate(Rs):
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
                other = (part_tri[c.b2] - p) @ R
                pts, ok = triangle_crossings(self.triangles[c.b1][None], other[None])
                pt = pts[0, ok[0]].mean(axis=0) if ok.any() else self.triangles[c.b1].mean(axis=0)
                best = (key[0], key[1], k, pt)
        assert best is not None
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
    )


def plan_weld_poses(
    part_or_cell: Any,
    route_or_joints: Any,
    tool: Tool,
    *,
    cone: float = DEFAULT_CONE,
    tilt_step: float = DEFAULT_TILT_STEP,
    spin_step: float = DEFAULT_SPIN_STEP,
    azimuths: int = DEFAULT_AZIMUTHS,
    contact_radius: float = DEFAULT_CONTACT_RADIUS,
    clearance: float | None = None,
) -> WeldPoses:
    """A verified collision-free tool pose for every weld, or its closest miss (module docstring).

    Parameters
    ----------
    part_or_cell
        The part mesh (mm) or a :class:`~weldplan.weld.cell.Cell` (its part, clearance, and
        virtual joints for the sign of surface normals).
    route_or_joints
        A :class:`~weldplan.weld.route.Route` (its visiting order),
        :class:`~weldplan.io.joints.Joints` (file order), or ``None`` to take the cell's joints.
    tool
        The tool (:mod:`weldplan.tool.model`).
    cone, tilt_step, spin_step, azimuths
        The candidate orientations (degrees; :func:`~weldplan.tool.orient.local_candidates`).
    contact_radius
        mm: the contact zone about the weld spot, exempt from the check.
    clearance
        mm: least distance between the tool outside the zone and the part; default the cell's
        clearance, else :data:`DEFAULT_CLEARANCE`.

    Returns
    -------
    WeldPoses
        In visiting order; every ``ok`` pose has passed the independent re-check.
    """
    t0 = time.perf_counter()
    cell = part_or_cell if hasattr(part_or_cell, "part") else None
    part = cell.part if cell is not None else part_or_cell
    if not isinstance(part, trimesh.Trimesh):
        raise TypeError("part_or_cell must be a trimesh.Trimesh or a Cell")
    if clearance is None:
        clearance = float(cell.clearance) if cell is not None else DEFAULT_CLEARANCE
    for name, val in (("clearance", clearance), ("contact_radius", contact_radius)):
        if not val >= 0:
            raise InputError(f"must be >= 0 mm, got {val}", field=name)
    welds = _welds(route_or_joints, cell)
    if welds.directions is not None:
        axes = -np.asarray(welds.directions, dtype=np.float64)
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    else:
        axes = surface_approach(part, welds.xyz, welds.free_points)
    local, params = local_candidates(cone, tilt_step, spin_step, azimuths)
    rots = candidate_rotations(axes, local)  # (n, c, 3, 3)
    quats = quat_wxyz(rots.reshape(-1, 3, 3)).reshape(len(welds.ids), len(local), 4)
    search = _Search(part, tool, contact_radius, clearance)
    objs = [search.part_near(p) for p in welds.xyz]
    # distance per candidate: 0 collides, NaN not measured yet, inf nothing near
    dists = np.full((len(welds.ids), len(local)), np.nan)
    for i, p in enumerate(welds.xyz):
        hit = search.collides(objs[i], p, rots[i])
        dists[i, hit] = 0.0
        if objs[i] is None or clearance == 0:
            dists[i, ~hit] = np.inf
    checker = PoseChecker(part, tool, contact_radius, clearance)
    choice, total, counts = _choose(welds, dists, rots, quats, search, objs, clearance, checker)
    misses: dict[int, Miss] = {}
    for i, p in enumerate(welds.xyz):
        if i not in choice:
            for k in np.flatnonzero(np.isnan(dists[i])):  # a miss is measured over all candidates
                dists[i, k] = search.distance(objs[i], p, rots[i, k])
            misses[i] = search.miss(objs[i], p, rots[i], dists[i], params)
    poses = _assemble(welds, axes, dists, quats, params, choice, misses)
    elapsed = time.perf_counter() - t0
    result = WeldPoses(
        poses=poses,
        tool=f"{tool.name} [{tool.source}]",
        total_rotation=total,
        settings={
            "cone": cone,
            "tilt_step": tilt_step,
            "spin_step": spin_step,
            "azimuths": azimuths,
            "contact_radius": contact_radius,
            "clearance": clearance,
        },
        stats={
            "candidates_per_weld": len(local),
            "collision_queries": int(dists.size),
            **counts,
            "total_s": round(elapsed, 3),
        },
    )
    log.info("%s (%.1f s)", result.summary().splitlines()[0], elapsed)
    return result


def _assemble(
    welds: _Welds,
    axes: NDArray,
    dists: NDArray,
    quats: NDArray,
    params: NDArray,
    choice: dict[int, int],
    misses: dict[int, Miss],
) -> tuple[WeldPose, ...]:
    """One :class:`WeldPose` per weld from the chosen candidates and the misses."""
    poses: list[WeldPose] = []
    for i, wid in enumerate(welds.ids):
        base = {
            "id": wid,
            "position": tuple(float(v) for v in welds.xyz[i]),
            "approach": tuple(float(v) for v in axes[i]),
            "n_collision_free": int(np.sum(dists[i] != 0)),
        }
        if i in choice:
            k = choice[i]
            poses.append(
                WeldPose(
                    status=OK,
                    quaternion=tuple(float(v) for v in quats[i, k]),  # type: ignore[arg-type]
                    spin=float(params[k, 0]),
                    tilt=float(params[k, 1]),
                    azimuth=float(params[k, 2]),
                    **base,
                )
            )
        else:
            poses.append(WeldPose(status=NO_FREE_POSE, quaternion=None, miss=misses.get(i), **base))
    return tuple(poses)


def _choose(
    welds: _Welds,
    dists: NDArray[np.float64],
    rots: NDArray[np.float64],
    quats: NDArray[np.float64],
    search: _Search,
    objs: list[fcl.CollisionObject | None],
    clearance: float,
    checker: PoseChecker,
) -> tuple[dict[int, int], float, dict[str, int]]:
    """The least-rotation choice over the free candidates, measuring clearances lazily.

    ``dists (n, c)`` holds 0 for colliding candidates and NaN where the clearance is not measured
    yet; it is filled in place. The DP runs over every candidate not known to fail; each chosen
    candidate whose clearance is unknown is measured, and a weld whose choice falls short has all
    its candidates measured before the DP runs again. When every chosen candidate is known to be
    free, each passes the independent re-check or is dropped and the DP runs again. The answer is
    the DP's optimum over the truly free candidates: every candidate it picks has been measured,
    and the candidates it passed over can only make the optimum over a superset no worse.

    Returns the chosen candidate per weld index (welds with none free are absent), the summed
    rotation (deg) and counts (distance queries, candidates the re-check rejected).
    """
    rejected = np.zeros(dists.shape, dtype=bool)
    passed: set[tuple[int, int]] = set()
    counts = {"distance_queries": 0, "recheck_rejected": 0}
    for _ in range(_MAX_ROUNDS):
        ok = ~rejected & ~(dists == 0) & ~(dists < clearance)  # NaN compares False: kept
        welds_ok = [i for i in range(len(dists)) if ok[i].any()]
        cand = [np.flatnonzero(ok[i]) for i in welds_ok]
        pick, total = least_rotation_choice(
            [quats[i, c] for i, c in zip(welds_ok, cand, strict=True)]
        )
        choice = {i: int(c[j]) for i, c, j in zip(welds_ok, cand, pick, strict=True)}
        short = []
        for i, k in choice.items():
            if np.isnan(dists[i, k]):
                dists[i, k] = search.distance(objs[i], welds.xyz[i], rots[i, k])
                counts["distance_queries"] += 1
                if dists[i, k] < clearance:
                    short.append(i)
        for i in short:  # measure the whole weld at once: bounds the rounds by the welds
            todo = np.flatnonzero(np.isnan(dists[i]))
            for k in todo:
                dists[i, k] = search.distance(objs[i], welds.xyz[i], rots[i, k])
            counts["distance_queries"] += len(todo)
        if short:
            continue
        bad = False
        for i, k in choice.items():
            if (i, k) in passed:
                continue
            out = checker.check(welds.xyz[i], quats[i, k])
            if out.ok:
                passed.add((i, k))
            else:
                log.warning("weld %s: the re-check rejected a pose: %s", welds.ids[i], out.reason)
                rejected[i, k] = bad = True
                counts["recheck_rejected"] += 1
        if not bad:
            return choice, total, counts
    raise RuntimeError("the pose choice did not settle: the re-check keeps rejecting poses (a bug)")
