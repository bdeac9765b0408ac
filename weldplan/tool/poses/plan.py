"""A collision-free tool pose for every weld: approach axis, spin, tilt, least rotation en route.

For each weld the tool's TCP sits on the weld spot with its +z axis along the approach axis (the
joints CSV's direction reversed: the CSV points from the joint towards the torch; without one,
the part's surface normal at the closest point, on the free side). Candidates spin about that
axis (every ``spin_step`` degrees) and tilt off it inside a cone (rings every ``tilt_step`` up
to ``cone`` degrees, ``azimuths`` directions per ring), :mod:`weldplan.tool.poses.orient`.

A tool that straddles the sheet (a C-gun, :attr:`~weldplan.tool.model.Tool.straddles`) may also
weld a spot **turned over**, the approach axis reversed: the electrodes clamp the sheet, so
either side is a legitimate approach. The turned-over candidates are tried only for a weld with
no free candidate on the approach side, or none the acceptance test accepts there (the joints
CSV's side stays the first choice, and the choice among welds free and accepted on that side is
what it was without turning over; :func:`_turn_over`).

A candidate is free when the tool **minus its part inside the contact zone** (the sphere of
``contact_radius`` mm about the TCP, i.e. about the weld spot, cut to the tool's tip cone for an
arc torch; :meth:`~weldplan.tool.model.Tool.outside_zone`) does not collide with the part and is
at least ``clearance`` mm from it (python-fcl ``collide``, then ``distance``, measured lazily:
only where the choice needs it). The FCL queries are in :mod:`weldplan.tool.poses.search`.

Among the free candidates, the pose of each weld is chosen by dynamic programming along the route
order so that the summed rotation between consecutive welds is least
(:func:`~weldplan.tool.poses.least_rotation_choice`); welds without a free pose are skipped in
that chain and reported with their closest miss. Every chosen pose is re-checked by
:class:`~weldplan.tool.verify.PoseChecker` (fresh FCL models of the whole part and tool)
before it is reported ok; a pose that fails is dropped from its weld's candidates and the choice
is made again. An optional acceptance test (``accept``: an exit exists, the robot reaches the
pose) then judges the picks, and a vetoed pick is dropped the same way, as a preference
(:mod:`weldplan.tool.poses.choice`).
"""

from __future__ import annotations

import logging
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.tool.model.tool import Tool
from weldplan.tool.poses.choice import Accept, Candidates, ChoiceState, choose
from weldplan.tool.poses.orient import candidate_rotations, local_candidates, rotation_angles
from weldplan.tool.poses.result import NO_FREE_POSE, OK, Miss, WeldPose, WeldPoses, quat_wxyz
from weldplan.tool.poses.search import PoseSearch, probe_positions
from weldplan.tool.settings import DEFAULT_CLEARANCE, PoseSearchSettings

# re-exported where it was declared before weldplan.tool.settings
from weldplan.tool.settings import DEFAULT_CONTACT_RADIUS as DEFAULT_CONTACT_RADIUS
from weldplan.tool.verify.poses import PoseCheck, PoseChecker

log = logging.getLogger(__name__)


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
    settings: PoseSearchSettings | None = None,
    *,
    accept: Accept | None = None,
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
        The tool (:mod:`weldplan.tool.model.tool`).
    settings
        The candidates, the contact zone, the clearance (default the cell's, else
        :data:`~weldplan.tool.settings.DEFAULT_CLEARANCE`), both sides or one, the cropped
        check and the acceptance test's vetoes (:class:`~weldplan.tool.settings.PoseSearchSettings`;
        default its defaults).
    accept
        An acceptance test of the picks beyond being free (an exit exists, the robot reaches
        it): ``accept(i, T)`` gets weld ``i`` (route order) and its TCP pose ``T (4, 4)`` mm and
        returns ``None`` or the reason it vetoes the pose. A preference: a weld whose free
        candidates are all vetoed, or that took ``settings.max_vetoes`` vetoes, keeps its
        least-rotation free pose with the reasons in :attr:`~weldplan.tool.poses.WeldPose.note`
        (:mod:`weldplan.tool.poses.choice`).

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
    s = settings if settings is not None else PoseSearchSettings()
    clearance = s.clearance
    if clearance is None:
        clearance = float(cell.clearance) if cell is not None else DEFAULT_CLEARANCE
    contact_radius = s.contact_radius
    welds = _welds(route_or_joints, cell)
    if welds.directions is not None:
        axes = -np.asarray(welds.directions, dtype=np.float64)
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    else:
        axes = surface_approach(part, welds.xyz, welds.free_points)
    both_sides = tool.straddles if s.both_sides is None else s.both_sides
    local, params = local_candidates(s.cone, s.tilt_step, s.spin_step, s.azimuths)
    params = np.column_stack([params, np.zeros(len(params))])  # spin, tilt, azimuth, flipped
    frame = _part_axes(cell)
    rots = candidate_rotations(axes, local, frame)  # (n, c, 3, 3)
    if both_sides:
        rots = np.concatenate([rots, candidate_rotations(-axes, local, frame)], axis=1)
        params = np.concatenate([params, params + [0.0, 0.0, 0.0, 1.0]])
    n, c = len(welds.ids), len(params)
    quats = quat_wxyz(rots.reshape(-1, 3, 3)).reshape(n, c, 4)
    own = None if frame is None else _own_quats(axes @ frame, local, both_sides)
    search = PoseSearch(part, tool, contact_radius, clearance, crop=s.crop)
    t_near = time.perf_counter()
    near = [search.part_near(p) for p in welds.xyz]
    objs = [o for o, _ in near]
    t_collide = time.perf_counter()
    table = _Table(search, objs, welds.xyz, rots, params[:, 3] == 1.0)
    for i in range(n):
        table.check(i, both_sides)
    dists, allowed, over = table.dists, table.allowed, table.over
    t_choose = time.perf_counter()
    checker = Rechecks.of(part, tool, contact_radius, clearance)
    state = ChoiceState(dists.shape)

    cands = Candidates(welds.xyz, tuple(welds.ids), rots, quats, own)

    def pick() -> tuple[dict[int, int], float]:
        return choose(
            cands, dists, allowed, search, objs, checker, state, accept=accept,
            max_vetoes=s.max_vetoes,
        )  # fmt: skip

    choice, total = pick()
    if both_sides:
        choice, total = _turn_over(table, state, choice, total, pick)
    t_miss = time.perf_counter()
    alts = _alternatives(
        dists, table.allowed & table.tried, state.rejected, quats, choice, clearance, own
    )
    misses = {i: table.miss(i, near[i][1], params) for i in range(n) if i not in choice}
    dists[~table.tried] = 0.0  # not tried: counted as not free below
    notes = {i: _veto_note(r) for i, r in state.veto_reasons.items() if i in state.exhausted}
    poses = _assemble(welds, axes, dists, quats, params, choice, misses, notes)
    elapsed = time.perf_counter() - t0
    result = WeldPoses(
        poses=poses,
        tool=f"{tool.name} [{tool.source}]",
        total_rotation=total,
        settings={
            "cone": s.cone,
            "tilt_step": s.tilt_step,
            "spin_step": s.spin_step,
            "azimuths": s.azimuths,
            "contact_radius": contact_radius,
            "clearance": clearance,
            "tip_cone": tool.tip_cone,
            "both_sides": bool(both_sides),
        },
        stats={
            "candidates_per_weld": c,
            "collision_queries": int(table.tried.sum()),
            "turned_over_tried": int(table.tried[:, over].any(axis=1).sum()),
            **state.counts,
            "accept_exhausted": len(state.exhausted),
            "crops_built": search.crops_built,
            **{f"clearance_{k}": v for k, v in search.bound_counts.items()},
            "setup_s": round(t_near - t0, 3),
            "broad_phase_s": round(t_collide - t_near, 3),
            "collide_s": round(t_choose - t_collide, 3),
            "choose_s": round(t_miss - t_choose, 3),
            "miss_s": round(time.perf_counter() - t_miss, 3),
            "total_s": round(elapsed, 3),
        },
        alternatives=alts,
    )
    log.info("%s (%.1f s)", result.summary().splitlines()[0], elapsed)
    return result


def _own_quats(axes: NDArray[np.float64], local: NDArray[np.float64], both: bool) -> NDArray:
    """``(n, c, 4)``: the candidates of the approach ``axes (n, 3)`` given in the part's own
    frame, as quaternions in that frame (:attr:`~weldplan.tool.poses.choice.Candidates.own`)."""
    rots = candidate_rotations(axes, local)
    if both:
        rots = np.concatenate([rots, candidate_rotations(-axes, local)], axis=1)
    return quat_wxyz(rots.reshape(-1, 3, 3)).reshape(rots.shape[0], rots.shape[1], 4)


def _part_axes(cell: Any) -> NDArray[np.float64] | None:
    """``(3, 3)``: the part frame's axes in the cell frame when ``cell`` placed the part by a
    pose (:attr:`~weldplan.weld.cell.Cell.part_pose`), else ``None``: the candidates' frames
    turn with the part (:func:`~weldplan.tool.poses.orient.nominal_frames`)."""
    pose = None if cell is None else getattr(cell, "part_pose", None)
    return None if pose is None else np.asarray(pose.matrix, dtype=np.float64)[:3, :3]


class Rechecks:
    """The re-check of the picks (:class:`~weldplan.tool.verify.PoseChecker`: its own
    FCL models of the whole part and tool, none shared with the search) and its verdicts, kept
    on the tool for the one part it was last asked about: a station's poses are searched twice
    (without the robot's test for the base search, then with it), and the second search's
    picks are mostly the first's. The same pose, the same verdict: only the work is saved (the
    models cost about 0.4 s to build on the shared gun, a check about 10 ms). The final
    re-check of the result (:func:`~weldplan.tool.verify.verify_poses`) builds its own.
    """

    def __init__(self, checker: PoseChecker) -> None:
        self.checker = checker
        self._seen: dict[tuple[bytes, bytes], PoseCheck] = {}

    @classmethod
    def of(cls, part: trimesh.Trimesh, tool: Tool, radius: float, clearance: float) -> Rechecks:
        """The re-check of ``part`` with ``tool`` (contact radius and clearance in mm), built
        once per part (cached on the tool, keyed by the settings; a new part replaces it)."""
        key = ("pose_rechecks", float(radius), float(clearance), tool.tip_cone)
        hit = tool._cache.get(key)
        if hit is None or hit[0]() is not part:
            hit = (weakref.ref(part), cls(PoseChecker(part, tool, radius, clearance)))
            tool._cache[key] = hit
        return hit[1]

    def check(self, position: ArrayLike, quaternion: ArrayLike) -> PoseCheck:
        """:meth:`PoseChecker.check <weldplan.tool.verify.PoseChecker.check>`, asked once
        per pose (TCP ``position (3,)`` mm, ``quaternion`` wxyz)."""
        p = np.asarray(position, dtype=np.float64).reshape(3)
        q = np.asarray(quaternion, dtype=np.float64).reshape(4)
        key = (p.tobytes(), q.tobytes())
        if key not in self._seen:
            self._seen[key] = self.checker.check(p, q)
        return self._seen[key]


def _turn_over(
    table: _Table,
    state: ChoiceState,
    choice: dict[int, int],
    total: float,
    pick: Callable[[], tuple[dict[int, int], float]],
) -> tuple[dict[int, int], float]:
    """Try the turned-over candidates of the welds that need them and choose again.

    A weld needs them when no approach-side candidate is free (they collide: tried already by
    :meth:`_Table.check`; or they fall short of the clearance) or when the acceptance test was
    lifted for it (every free approach-side candidate vetoed, or ``max_vetoes`` reached): the test
    is put back on it (:meth:`ChoiceState.reopen`) over its turned-over candidates only, the
    approach side counting as not accepted. A weld whose turned-over candidates are all vetoed
    too keeps its least-rotation approach-side pose, as without the test (the joints CSV's side
    stays the first choice): its turned-over candidates are withdrawn.
    """
    over, allowed = table.over, table.allowed
    short = [i for i in range(len(allowed)) if i not in choice and not allowed[i, over].any()]
    vetoed = sorted(i for i in state.exhausted if not allowed[i, over].any())
    for i in short + vetoed:
        table.turn_over(i)
    for i in vetoed:  # the test again, over the turned-over candidates only
        state.reopen(i)
        state.vetoed[i, ~over] = True
    if not (short or vetoed):
        return choice, total
    choice, total = pick()
    back = [i for i in vetoed if i in state.exhausted]
    for i in back:
        allowed[i, over] = False  # still counted as tried (table.tried)
    return pick() if back else (choice, total)


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
        #: the candidates collided (``allowed`` less those withdrawn again)
        self.tried = self.allowed.copy()
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
        self.tried[i, which] = True

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
        """Weld ``i``'s closest miss over its tried candidates, their clearances measured.

        The choice's values are bounds (:meth:`PoseSearch.clearances`); the miss ranks by the
        distance itself, so the candidates that could hold the largest are measured by FCL:
        every unmeasured one, every one at the clearance or above (a re-checked pick), and the
        short ones in order of their upper bounds while one could still beat the best."""
        mine = np.flatnonzero(self.allowed[i])
        d = self.dists[i]

        def measure(k: int) -> None:
            d[k] = self.search.distance(self.objs[i], self.xyz[i], self.rots[i, k])

        dm, c = d[mine], self.search.clearance
        with np.errstate(invalid="ignore"):
            short = (dm > 0) & (dm < c)
            redo = np.isnan(dm) | ((dm >= c) & np.isfinite(dm))
        for k in mine[redo]:
            measure(int(k))
        best = float(np.max(d[mine[~short]], initial=0.0))
        short = mine[short]
        for k in short[np.argsort(-d[short], kind="stable")]:
            if d[k] < best:
                break  # an upper bound below the best distance measured: it cannot win
            measure(int(k))
            best = max(best, float(d[k]))
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
    notes: dict[int, str],
) -> tuple[WeldPose, ...]:
    """One :class:`WeldPose` per weld from the chosen candidates, the misses and the notes."""
    poses: list[WeldPose] = []
    for i, wid in enumerate(welds.ids):
        base = {
            "id": wid,
            "position": tuple(float(v) for v in welds.xyz[i]),
            "n_collision_free": int(np.sum(dists[i] != 0)),
            "note": notes.get(i, ""),
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


def _alternatives(
    dists: NDArray[np.float64],
    live: NDArray[np.bool_],
    rejected: NDArray[np.bool_],
    quats: NDArray[np.float64],
    choice: dict[int, int],
    clearance: float,
    own: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], ...]:
    """Per weld, the quaternions of its candidates not known to fail for the tool
    (:attr:`~weldplan.tool.poses.WeldPoses.alternatives`): tried and still allowed (``live``),
    not colliding (``dists != 0``), clearance not measured short (NaN or at least the clearance:
    :func:`_first_free` stops at the first that keeps it), not rejected by the re-check; the
    chosen one first, then by rotation from it (measured on ``own``, the candidates in the
    part's frame, when given)."""
    own = quats if own is None else own
    out: list[NDArray[np.float64]] = []
    for i in range(len(dists)):
        if i not in choice:
            out.append(np.zeros((0, 4)))
            continue
        c = choice[i]
        d = dists[i]
        with np.errstate(invalid="ignore"):
            k = np.flatnonzero(live[i] & ~rejected[i] & (d != 0) & ~(d < clearance))
        k = k[k != c]
        ang = rotation_angles(own[i, k], own[i, c][None])[:, 0]
        out.append(np.concatenate([quats[i, [c]], quats[i, k[np.argsort(ang, kind="stable")]]]))
    return tuple(out)


def _veto_note(reasons: list[str]) -> str:
    """A weld's note when the acceptance test was lifted for it: how many free poses it vetoed,
    and the first reason."""
    n = len(reasons)
    return f"{n} free pose{'s' if n > 1 else ''} vetoed ({reasons[0]}); kept the least-rotation one"
