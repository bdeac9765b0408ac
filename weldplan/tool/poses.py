"""A collision-free tool pose for every weld: approach axis, spin, tilt, least rotation en route.

For each weld the tool's TCP sits on the weld spot with its +z axis along the approach axis (the
joints CSV's direction reversed: the CSV points from the joint towards the torch; without one,
the part's surface normal at the closest point, on the free side). Candidates spin about that
axis (every ``spin_step`` degrees) and tilt off it inside a cone (rings every ``tilt_step`` up
to ``cone`` degrees, ``azimuths`` directions per ring), :mod:`weldplan.tool.orient`.

A tool that straddles the sheet (a C-gun, :attr:`~weldplan.tool.model.Tool.straddles`) may also
weld a spot **turned over**, the approach axis reversed: the electrodes clamp the sheet, so
either side is a legitimate approach. The turned-over candidates are tried only for a weld with
no free candidate on the approach side (the joints CSV's side stays the first choice, and the
choice among welds free on that side is what it was without turning over).

A candidate is free when the tool **minus its part inside the contact zone** (the sphere of
``contact_radius`` mm about the TCP, i.e. about the weld spot, cut to the tool's tip cone for an
arc torch; :meth:`~weldplan.tool.model.Tool.outside_zone`) does not collide with the part and is
at least ``clearance`` mm from it (python-fcl ``collide``, then ``distance``, measured lazily:
only where the choice needs it). The FCL queries are in :mod:`weldplan.tool.pose_search`.

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
from weldplan.tool.model import Tool
from weldplan.tool.orient import (
    candidate_rotations,
    least_rotation_choice,
    local_candidates,
    rotation_angles,
)
from weldplan.tool.pose_search import PoseSearch, probe_positions
from weldplan.tool.result import NO_FREE_POSE, OK, Miss, WeldPose, WeldPoses, quat_wxyz
from weldplan.tool.verify_poses import PoseChecker

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
    both_sides: bool | None = None,
    crop: bool = True,
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
    both_sides
        Also try every candidate turned over (the approach axis reversed: the tool on the other
        side of the sheet), after the candidates on the approach side, so that ties keep the
        approach side. Default: the tool's :attr:`~weldplan.tool.model.Tool.straddles` (a C-gun
        clamps the sheet and welds it from either side; an arc torch does not).
    crop
        Check against a BVH per weld of the part cropped to the tool's reach (default), or
        against one BVH of the whole part (:class:`~weldplan.tool.pose_search.PoseSearch`; the
        same answers).

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
    if both_sides is None:
        both_sides = tool.straddles
    local, params = local_candidates(cone, tilt_step, spin_step, azimuths)
    params = np.column_stack([params, np.zeros(len(params))])  # spin, tilt, azimuth, flipped
    rots = candidate_rotations(axes, local)  # (n, c, 3, 3)
    if both_sides:
        rots = np.concatenate([rots, candidate_rotations(-axes, local)], axis=1)
        params = np.concatenate([params, params + [0.0, 0.0, 0.0, 1.0]])
    n, c = len(welds.ids), len(params)
    quats = quat_wxyz(rots.reshape(-1, 3, 3)).reshape(n, c, 4)
    search = PoseSearch(part, tool, contact_radius, clearance, crop=crop)
    t_near = time.perf_counter()
    near = [search.part_near(p) for p in welds.xyz]
    objs = [o for o, _ in near]
    t_collide = time.perf_counter()
    table = _Table(search, objs, welds.xyz, rots, params[:, 3] == 1.0)
    for i in range(n):
        table.check(i, both_sides)
    dists, allowed, over = table.dists, table.allowed, table.over
    t_choose = time.perf_counter()
    checker = PoseChecker(part, tool, contact_radius, clearance)
    state = _ChoiceState(dists.shape)
    choice, total = _choose(welds, dists, allowed, rots, quats, search, objs, checker, state)
    turn = [i for i in range(n) if both_sides and i not in choice and not allowed[i, over].any()]
    for i in turn:  # free of collision on the approach side, but short of the clearance
        table.turn_over(i)
    if turn:
        choice, total = _choose(welds, dists, allowed, rots, quats, search, objs, checker, state)
    t_miss = time.perf_counter()
    misses = {i: table.miss(i, near[i][1], params) for i in range(n) if i not in choice}
    dists[~allowed] = 0.0  # not tried: counted as not free below
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
            "tip_cone": tool.tip_cone,
            "both_sides": bool(both_sides),
        },
        stats={
            "candidates_per_weld": c,
            "collision_queries": int(allowed.sum()),
            "turned_over_tried": int(allowed[:, over].any(axis=1).sum()),
            **state.counts,
            "crops_built": search.crops_built,
            "setup_s": round(t_near - t0, 3),
            "broad_phase_s": round(t_collide - t_near, 3),
            "collide_s": round(t_choose - t_collide, 3),
            "choose_s": round(t_miss - t_choose, 3),
            "miss_s": round(time.perf_counter() - t_miss, 3),
            "total_s": round(elapsed, 3),
        },
    )
    log.info("%s (%.1f s)", result.summary().splitlines()[0], elapsed)
    return result


class _Table:
    """Every weld's candidates and what is known of them.

    ``dists (n, c)``: 0 where a candidate collides, NaN where its clearance is not measured yet,
    ``inf`` where nothing of the part is near; ``allowed (n, c)``: the candidates tried (the
    approach side, and the turned-over ones, ``over (c,)``, of welds that needed them).
    """

    def __init__(
        self,
        search: PoseSearch,
        objs: list[fcl.CollisionObject | None],
        xyz: NDArray[np.float64],
        rots: NDArray[np.float64],
        over: NDArray[np.bool_],
    ) -> None:
        self.search, self.objs, self.xyz, self.rots, self.over = search, objs, xyz, rots, over
        self.dists = np.full(rots.shape[:2], np.nan)
        self.allowed = np.tile(~over, (len(xyz), 1))
        # the closest-miss probe's counts, taken with the collision queries (-1: not taken)
        self.touch = np.full(rots.shape[:2], -1, dtype=np.int64)
        self.probe = np.zeros(rots.shape[1], dtype=bool)
        self.probe[probe_positions(rots.shape[1])] = True

    def _collide(self, i: int, which: NDArray[np.bool_]) -> None:
        probe = self.probe[which]
        count = self.search.touching(self.objs[i], self.xyz[i], self.rots[i, which], probe)
        self.touch[i, np.flatnonzero(which)[probe]] = count[probe]
        hit = count > 0
        far = self.objs[i] is None or self.search.clearance == 0
        self.dists[i, which] = np.where(hit, 0.0, np.inf if far else np.nan)
        self.allowed[i, which] = True

    def check(self, i: int, both_sides: bool) -> None:
        """Collide weld ``i``'s approach-side candidates, and its turned-over ones too when
        ``both_sides`` and every one on the approach side collides."""
        self._collide(i, ~self.over)
        if both_sides and np.all(self.dists[i, ~self.over] == 0):
            self._collide(i, self.over)

    def turn_over(self, i: int) -> None:
        """Try weld ``i``'s turned-over candidates as well."""
        self._collide(i, self.over)

    def miss(self, i: int, index: NDArray[np.int64], params: NDArray[np.float64]) -> Miss:
        """Weld ``i``'s closest miss over its tried candidates, their clearances measured."""
        mine = np.flatnonzero(self.allowed[i])
        for k in mine[np.isnan(self.dists[i, mine])]:
            self.dists[i, k] = self.search.distance(self.objs[i], self.xyz[i], self.rots[i, k])
        return self.search.miss(
            self.objs[i], index, self.xyz[i], self.rots[i, mine], self.dists[i, mine],
            params[mine], self.touch[i, mine],
        )  # fmt: skip


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
            "n_collision_free": int(np.sum(dists[i] != 0)),
        }
        if i in choice:
            k = choice[i]
            flipped = bool(params[k, 3])
            poses.append(
                WeldPose(
                    status=OK,
                    approach=tuple(float(v) for v in (-axes[i] if flipped else axes[i])),
                    quaternion=tuple(float(v) for v in quats[i, k]),  # type: ignore[arg-type]
                    spin=float(params[k, 0]),
                    tilt=float(params[k, 1]),
                    azimuth=float(params[k, 2]),
                    flipped=flipped,
                    **base,
                )
            )
        else:
            poses.append(
                WeldPose(
                    status=NO_FREE_POSE,
                    approach=tuple(float(v) for v in axes[i]),
                    quaternion=None,
                    miss=misses.get(i),
                    **base,
                )
            )
    return tuple(poses)


def _first_free(
    i: int,
    ref: NDArray[np.float64],
    dists: NDArray[np.float64],
    allowed: NDArray[np.bool_],
    rots: NDArray[np.float64],
    quats: NDArray[np.float64],
    search: PoseSearch,
    obj: fcl.CollisionObject | None,
    p: NDArray[np.float64],
) -> int:
    """Measure weld ``i``'s unmeasured candidates in order of their summed rotation to ``ref
    (r, 4)`` (the neighbours' current picks) until one keeps the clearance; returns the count.

    The order only decides which measurements come first: the DP that runs next still sees every
    candidate not known to fail, so the final choice is the same optimum (see :func:`_choose`).
    """
    todo = np.flatnonzero(np.isnan(dists[i]) & allowed[i])
    cost = rotation_angles(quats[i, todo], ref).sum(axis=1)
    for n, k in enumerate(todo[np.argsort(cost, kind="stable")], start=1):
        dists[i, k] = search.distance(obj, p, rots[i, k])
        if dists[i, k] >= search.clearance:
            return n
    return len(todo)


class _ChoiceState:
    """What :func:`_choose` learns that stays true across calls: poses the re-check rejected or
    passed, and counts."""

    def __init__(self, shape: tuple[int, int]) -> None:
        self.rejected = np.zeros(shape, dtype=bool)
        self.passed: set[tuple[int, int]] = set()
        self.counts = {"distance_queries": 0, "recheck_rejected": 0, "choice_rounds": 0}
        self._angles: dict[tuple[int, int], tuple[NDArray, NDArray, NDArray]] = {}

    def angles(
        self, quats: NDArray, i: int, ci: NDArray[np.int64], j: int, cj: NDArray[np.int64]
    ) -> NDArray[np.float64]:
        """``(len(ci), len(cj))`` degrees between candidates ``ci`` of weld ``i`` and ``cj`` of
        weld ``j``, cut from a matrix cached per pair of welds (the DP's rounds shrink the
        candidate sets; the angles do not change)."""
        hit = self._angles.get((i, j))
        if hit is None or not (np.isin(ci, hit[0]).all() and np.isin(cj, hit[1]).all()):
            hit = (ci, cj, rotation_angles(quats[i, ci], quats[j, cj]))
            self._angles[(i, j)] = hit
        a, b, m = hit
        return m[np.ix_(np.searchsorted(a, ci), np.searchsorted(b, cj))]


def _choose(
    welds: _Welds,
    dists: NDArray[np.float64],
    allowed: NDArray[np.bool_],
    rots: NDArray[np.float64],
    quats: NDArray[np.float64],
    search: PoseSearch,
    objs: list[fcl.CollisionObject | None],
    checker: PoseChecker,
    state: _ChoiceState,
) -> tuple[dict[int, int], float]:
    """The least-rotation choice over the free candidates, measuring clearances lazily.

    ``dists (n, c)`` holds 0 for colliding candidates and NaN where the clearance is not measured
    yet; it is filled in place. Only ``allowed (n, c)`` candidates take part. The DP runs over
    every candidate not known to fail; each chosen candidate whose clearance is unknown is
    measured, and a weld whose choice falls short has its other candidates measured, least
    rotation from its neighbours' picks first, up to the first that keeps the clearance
    (:func:`_first_free`), before the DP runs again. When every chosen candidate is known to be
    free, each passes the independent re-check or is dropped and the DP runs again. The answer
    is the DP's optimum over the truly free candidates: every candidate it picks has been
    measured, and the candidates it passed over can only make the optimum over a superset no
    worse. Every round that does not return measures or rejects at least one candidate, so the
    rounds are at most twice the candidates.

    Returns the chosen candidate per weld index (welds with none free are absent) and the summed
    rotation (deg); counts (distance queries, candidates the re-check rejected) go to ``state``.
    """
    clearance = search.clearance
    counts = state.counts
    for _ in range(2 * dists.size + 1):
        counts["choice_rounds"] += 1
        ok = allowed & ~state.rejected & ~(dists == 0) & ~(dists < clearance)  # NaN: kept
        welds_ok = [i for i in range(len(dists)) if ok[i].any()]
        cand = [np.flatnonzero(ok[i]) for i in welds_ok]
        pick, total = least_rotation_choice(
            [quats[i, c] for i, c in zip(welds_ok, cand, strict=True)],
            lambda k, w=welds_ok, c=cand: state.angles(quats, w[k - 1], c[k - 1], w[k], c[k]),
        )
        choice = {i: int(c[j]) for i, c, j in zip(welds_ok, cand, pick, strict=True)}
        short = []
        for i, k in choice.items():
            if np.isnan(dists[i, k]):
                dists[i, k] = search.distance(objs[i], welds.xyz[i], rots[i, k])
                counts["distance_queries"] += 1
                if dists[i, k] < clearance:
                    short.append(i)
        if short:
            chain = list(choice)  # the welds with a pick, in route order
            for i in short:
                j = chain.index(i)
                nbrs = [chain[m] for m in (j - 1, j + 1) if 0 <= m < len(chain)]
                ref = quats[nbrs, [choice[m] for m in nbrs]] if nbrs else quats[i, [choice[i]]]
                counts["distance_queries"] += _first_free(
                    i, ref, dists, allowed, rots, quats, search, objs[i], welds.xyz[i]
                )
            continue
        bad = False
        for i, k in choice.items():
            if (i, k) in state.passed:
                continue
            out = checker.check(welds.xyz[i], quats[i, k])
            if out.ok:
                state.passed.add((i, k))
            else:
                log.warning("weld %s: the re-check rejected a pose: %s", welds.ids[i], out.reason)
                state.rejected[i, k] = bad = True
                counts["recheck_rejected"] += 1
        if not bad:
            return choice, total
    raise RuntimeError("the pose choice did not settle: the re-check keeps rejecting poses (a bug)")
