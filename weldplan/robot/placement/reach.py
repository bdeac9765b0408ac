"""Reach: which flange poses a robot can take, why not, and where to put the robot.

A pose is *usable* on a branch when the branch exists (the wrist centre is inside the arm's
reachable annulus), every joint is within its limits, and the wrist is farther from its
singularity than ``singular_deg`` (``|sin(theta5)| >= sin(singular_deg)``: A4 and A6 aligned at
``theta5 = 0``). A pose with no usable branch gets the first reason that applies:

- :data:`OUT_OF_REACH`: no branch exists and the wrist centre is out of the arm's reach
  (the solver's ``extension < 0``);
- :data:`JOINT_LIMIT`: branches exist, none within the joint limits;
- :data:`SINGULAR`: branches within the limits exist, all of them near the wrist singularity; or
  the wrist centre is within reach and yet no branch exists (py-opw-kinematics drops a branch
  exactly at ``theta5 = 0``, where A4 and A6 are not separable).

Placement (:func:`search_base`, then :func:`weldplan.robot.route.plan_robot_route` re-scores its
best few along the whole route): candidate base poses on the floor (a square grid about the weld
poses, on the plane ``z = floor_z`` of the planning frame and the pedestal planes above it; with
the part placed in a cell, :mod:`weldplan.cellframe`, that is the cell's floor, z up) or along a
line, each turned to face the welds (A1 then works about the middle of its
range; more yaws on request). Candidates whose base column would stand in the part are dropped
(a capsule about A1 from the floor to the A2 axis, radius the base's and A1 link's extent,
checked by exact point-surface distance). A candidate is scored by the number of welds it makes
usable, then by the smallest over those welds of the best manipulability over their usable
branches (:meth:`~weldplan.robot.model.Robot.manipulability`); the best one wins. Candidates
stand at every pedestal height (:attr:`BaseSearch.heights`) and yaw (the facing one plus
:attr:`BaseSearch.extra_yaws`); with more than :data:`SCORE_WELDS` welds a first pass on that many
evenly spread welds keeps the best :data:`PRESELECT` for the full score. With a part, a weld
counts for a candidate only where the chord from its shoulder to the weld's wrist centre misses
the part (:func:`sight_clear`, a proxy for the arm passing through the body; when it rules out
every candidate, reach alone counts).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError
from weldplan.robot.model.arm import Robot
from weldplan.robot.model.ik import IKBranches

log = logging.getLogger(__name__)

#: weld / waypoint status words (RobotRoute carries them)
OK = "ok"
OUT_OF_REACH = "out_of_reach"
JOINT_LIMIT = "joint_limit"
SINGULAR = "singular"
COLLISION = "collision"
NO_POSE = "no_pose"
#: default wrist-singularity threshold (deg of A5 from 0)
DEFAULT_SINGULAR_DEG = 5.0
#: default floor-grid spacing for the base search (mm)
DEFAULT_STEP = 250.0
#: default pedestal heights (mm above the floor) and yaws added to the facing one (deg)
DEFAULT_HEIGHTS = (0.0, 400.0, 800.0)
DEFAULT_EXTRA_YAWS = (-30.0, 30.0)
#: with more welds than this, candidates are first scored on this many evenly spread welds and
#: only the best :data:`PRESELECT` are scored on all of them (the IK of every candidate at every
#: weld was most of a 200-weld search)
SCORE_WELDS = 48
PRESELECT = 256
#: decimals of the manipulability the rankings compare: candidates that differ only by round-off
#: (the same stand turned about A1's axis, whose configurations differ only in A1, have the
#: same manipulability up to 1e-16) tie, and the search's order (the facing yaw first) decides,
#: not the last bits of a floating-point sum, which differ with the machine's BLAS
TIE_DECIMALS = 9
#: mm: how far beyond :func:`arm_reach` a wrist centre must lie for :func:`may_reach` to skip its
#: IK (the solver's own out-of-reach test is exact; this only keeps round-off out of the way)
REACH_SLACK_MM = 1.0


def base_pose(x: float, y: float, z: float, yaw_deg: float) -> NDArray[np.float64]:
    """``(4, 4)``: a robot base at ``(x, y, z)`` mm in the planning frame (the cell frame when
    the part has a pose in the cell), turned ``yaw_deg`` about its z axis (the floor normal)."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    B = np.eye(4)
    B[:2, :2] = [[c, -s], [s, c]]
    B[:3, 3] = [x, y, z]
    return B


def parse_base(text: str, fld: str = "--robot-base") -> NDArray[np.float64]:
    """``"x,y,z,yaw"`` (mm, mm, mm, deg) -> :func:`base_pose`, else a one-line InputError."""
    parts = text.replace(";", ",").split(",")
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"not four numbers x,y,z,yaw: {text!r}", field=fld) from None
    if len(vals) != 4 or not all(math.isfinite(v) for v in vals):
        raise InputError(f"need four finite numbers x,y,z,yaw (mm, deg), got {text!r}", field=fld)
    return base_pose(*vals)


def usable(br: IKBranches, singular_deg: float = DEFAULT_SINGULAR_DEG) -> NDArray[np.bool_]:
    """``(n, 8) bool``: the branches usable for each pose (module docstring)."""
    thr = math.sin(math.radians(singular_deg))
    with np.errstate(invalid="ignore"):
        return br.in_limits & (np.nan_to_num(br.wrist) >= thr)


def classify(br: IKBranches, singular_deg: float = DEFAULT_SINGULAR_DEG) -> NDArray[np.str_]:
    """``(n,)`` status per pose: :data:`OK` or the reason it has no usable branch."""
    ok = usable(br, singular_deg).any(axis=1)
    out = np.full(len(ok), OK, dtype=object)
    out[~ok & br.in_limits.any(axis=1)] = SINGULAR
    out[~ok & ~br.in_limits.any(axis=1)] = JOINT_LIMIT
    none = ~ok & ~br.exists.any(axis=1)
    out[none] = np.where(br.extension[none] < 0, OUT_OF_REACH, SINGULAR)
    return out.astype(str)


@dataclass(frozen=True)
class BaseSearch:
    """Where :func:`search_base` looks for a base pose.

    Attributes
    ----------
    floor_z
        mm: the floor height in the planning frame: the cell's floor
        (:attr:`weldplan.cellframe.PartPose.floor_z`) when the part was placed in a cell, and
        the floor the robot is then checked against; default (a station in the part frame, no
        floor known): the part's lowest point, not checked.
    line
        ``((x, y, z), (x, y, z))`` mm: search along this segment instead of the floor.
    step
        mm between candidate positions.
    extra_yaws
        Degrees added to the facing yaw, each a further candidate (default
        :data:`DEFAULT_EXTRA_YAWS`).
    half_width
        mm: half the floor grid's side, about the welds' centre (default: the arm's reach).
    heights
        mm: pedestal heights tried at every floor position (the base at ``floor_z + h``; the
        pedestal is the base column's extension down to the floor). Default
        :data:`DEFAULT_HEIGHTS`. Not used with ``line`` (its points are the base).
    keep_out
        ``((x, y, r), ...)`` mm: discs of the floor where no base may stand (a base closer than
        ``r`` to ``(x, y)`` in the plane is no candidate): the footprints of robots already
        placed in a station of several (:mod:`weldplan.multi.cell`). Empty: none.
    """

    floor_z: float | None = None
    line: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None
    step: float = DEFAULT_STEP
    extra_yaws: tuple[float, ...] = DEFAULT_EXTRA_YAWS
    half_width: float | None = None
    heights: tuple[float, ...] = DEFAULT_HEIGHTS
    keep_out: tuple[tuple[float, float, float], ...] = ()

    def __post_init__(self) -> None:
        if self.floor_z is not None and not math.isfinite(self.floor_z):
            raise InputError(
                f"the floor must be a finite z in mm, got {self.floor_z}", field="floor_z"
            )
        h = np.asarray(self.heights, dtype=np.float64)
        if h.ndim != 1 or len(h) == 0 or not np.all(np.isfinite(h)) or np.any(h < 0):
            raise InputError(
                f"pedestal heights must be finite numbers >= 0 mm, got {self.heights!r}",
                field="heights",
            )
        k = np.asarray(self.keep_out, dtype=np.float64).reshape(-1, 3)
        if not np.all(np.isfinite(k)) or np.any(k[:, 2] < 0):
            raise InputError(
                f"keep-out discs must be finite (x, y, r >= 0) mm, got {self.keep_out!r}",
                field="keep_out",
            )

    def outside(self, pts: NDArray[np.float64]) -> NDArray[np.bool_]:
        """``(k,) bool``: which of ``pts (k, 3)`` mm stand outside every :attr:`keep_out` disc
        (distance in x, y at least its radius)."""
        ok = np.ones(len(pts), dtype=bool)
        for x, y, r in self.keep_out:
            ok &= np.hypot(pts[:, 0] - x, pts[:, 1] - y) >= r
        return ok


@dataclass(frozen=True)
class Placement:
    """The chosen base and how well it does.

    Attributes
    ----------
    base
        ``(4, 4)`` mm, part frame.
    n_usable
        Welds with a usable branch from it (of ``n_welds``; with a part, only those whose
        shoulder-wrist chord misses it: :func:`sight_clear`).
    min_manipulability
        The smallest, over those welds, of the best manipulability of their usable branches.
    candidates
        Candidate bases scored (after the part-overlap filter).
    searched
        ``False`` when the base was given.
    """

    base: NDArray[np.float64]
    n_usable: int
    n_welds: int
    min_manipulability: float
    candidates: int
    searched: bool
    #: which welds one roadmap joins at this base
    #: (:class:`weldplan.robot.placement.roadmaps.WeldJoin`; ``None``: not judged)
    join: Any = field(default=None, compare=False, repr=False)
    #: per base the transfer trial judged, best first: the welds it leaves out and why
    #: (:class:`weldplan.robot.placement.base.BaseVerdict`; empty: none judged)
    verdicts: tuple[Any, ...] = field(default=(), compare=False, repr=False)

    def xyz_yaw(self) -> tuple[float, float, float, float]:
        """``(x, y, z, yaw_deg)`` of :attr:`base` (the ``--robot-base`` form)."""
        yaw = math.degrees(math.atan2(self.base[1, 0], self.base[0, 0]))
        return (*(float(v) for v in self.base[:3, 3]), yaw)


def arm_reach(robot: Robot) -> float:
    """mm: an upper bound of the wrist centre's distance from the A2 axis (``c2 + |(c3, a2)|``)."""
    p = robot.opw
    return p.c2 + math.hypot(p.c3, p.a2)


def score_bases(
    robot: Robot,
    T_flange: NDArray[np.float64],
    bases: NDArray[np.float64],
    singular_deg: float = DEFAULT_SINGULAR_DEG,
    clear: NDArray[np.bool_] | None = None,
    more: Callable[[NDArray[np.bool_]], tuple[NDArray, NDArray]] | None = None,
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """Per candidate base ``(c, 4, 4)``: welds usable ``(c,)`` and smallest best manipulability
    ``(c,)`` over flange poses ``(n, 4, 4)`` (mm, part frame). Manipulability is computed only
    for the candidates that reach the most welds (the others cannot win). ``clear (c, n)``: a
    weld counts only where it is True (:func:`sight_clear`). ``more(served (c, n)) -> (got (c,
    n) bool, manipulability (c, n))``: welds served otherwise where ``served`` is False (by an
    alternative tool pose, :mod:`weldplan.robot.placement.altreach`); they count, and their
    manipulability joins the minimum."""
    n, c = len(T_flange), len(bases)
    at_origin = robot.with_base(np.eye(4))
    Tb = np.linalg.inv(bases)[:, None] @ T_flange[None]  # (c, n, 4, 4) in each base's frame
    # IK only where the wrist centre may be in reach: elsewhere no branch exists
    maybe = may_reach(robot, Tb)
    at = np.full((c, n), -1, dtype=np.int64)
    at[maybe] = np.arange(int(maybe.sum()))
    br = at_origin.ik_all(Tb[maybe])
    u_all = np.zeros((c, n, 8), dtype=bool)
    u_all[maybe] = usable(br, singular_deg)
    if clear is not None:
        u_all &= clear[:, :, None]
    served = u_all.any(axis=2)
    got, m_more = (np.zeros((c, n), dtype=bool), None) if more is None else more(served)
    counts = (served | got).sum(axis=1).astype(np.int64)
    mins = np.full(c, -np.inf)
    if n == 0 or c == 0:
        return counts, mins
    top = np.flatnonzero(counts == counts.max())
    # the usable branches of every leading candidate in one batch (the Jacobian and its SVD
    # are taken matrix by matrix, so the values are those of one call per candidate)
    idxs = [np.argwhere(u_all[i]) for i in top]
    qs = [br.q[at[i, idx[:, 0]], idx[:, 1]] for i, idx in zip(top, idxs, strict=True)]
    sizes = [len(q) for q in qs]
    m_all = at_origin.manipulability(np.concatenate(qs)) if sum(sizes) else np.zeros(0)
    m_each = np.split(m_all, np.cumsum(sizes)[:-1])
    for i, idx, m in zip(top, idxs, m_each, strict=True):
        best = np.full(n, -np.inf)
        if len(idx):
            np.maximum.at(best, idx[:, 0], m)
        if m_more is not None:
            best = np.where(served[i], best, np.where(got[i], m_more[i], -np.inf))
        if np.isfinite(best).any():
            mins[i] = float(best[np.isfinite(best)].min())
    return counts, mins


def may_reach(robot: Robot, T_base_flange: NDArray[np.float64]) -> NDArray[np.bool_]:
    """``(...) bool``: whether the wrist centre of each flange pose ``(..., 4, 4)`` (mm, robot
    base frame) may be within the arm's reach; ``False`` only where no IK branch can exist.

    The A2 axis passes through a point on the circle of radius ``hypot(a1, b)`` at height
    ``c1`` about A1, and the wrist centre (``c4`` behind the flange) stays within
    :func:`arm_reach` of it: a wrist centre farther than that (plus :data:`REACH_SLACK_MM`)
    from the whole circle is out of reach on every branch.
    """
    p = robot.opw
    T = np.asarray(T_base_flange, dtype=np.float64)
    wc = T[..., :3, 3] - p.c4 * T[..., :3, 2]
    gap = np.hypot(np.hypot(wc[..., 0], wc[..., 1]) - math.hypot(p.a1, p.b), wc[..., 2] - p.c1)
    return gap <= arm_reach(robot) + REACH_SLACK_MM


def sight_clear(
    robot: Robot, bases: NDArray[np.float64], T_flange: NDArray[np.float64], distance: object
) -> NDArray[np.bool_]:
    """``(c, n) bool``: the segment from each base's shoulder (the A2 axis, turned towards the
    weld) to each weld pose's wrist centre (``c4`` behind the flange) crosses no part triangle
    (open3d ray cast through ``distance``, a :class:`~weldplan.geometry.distance.SurfaceDistance`).
    A ranking proxy, not a check: the upper arm and forearm lie about that chord, so a part
    across it usually means a link through the part."""
    c, n = len(bases), len(T_flange)
    B = np.broadcast_to(bases[:, None], (c, n, 4, 4))
    T = np.broadcast_to(T_flange[None], (c, n, 4, 4))
    return chord_clear(robot, B.reshape(-1, 4, 4), T.reshape(-1, 4, 4), distance).reshape(c, n)


def chord_clear(
    robot: Robot, bases: NDArray[np.float64], T_flange: NDArray[np.float64], distance: object
) -> NDArray[np.bool_]:
    """``(p,) bool``: :func:`sight_clear` of pairs, base ``bases[i]`` to flange pose
    ``T_flange[i]`` (both ``(p, 4, 4)`` mm, part frame)."""
    p = robot.opw
    wc = T_flange[:, :3, 3] - p.c4 * T_flange[:, :3, 2]  # (p, 3)
    z = bases[:, :3, 2]
    o = bases[:, :3, 3] + p.c1 * z
    d = wc - o
    h = d - np.einsum("pi,pi->p", d, z)[:, None] * z
    h /= np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-9)
    sh = o + p.a1 * h
    seg = wc - sh
    L = np.linalg.norm(seg, axis=1)
    u = seg / np.maximum(L, 1e-9)[:, None]
    if len(L) == 0:
        return np.ones(0, dtype=bool)
    return distance.first_hit(sh, u) >= L  # type: ignore[attr-defined]


def candidate_bases(
    robot: Robot,
    T_flange: NDArray[np.float64],
    part: object | None,
    opts: BaseSearch,
) -> NDArray[np.float64]:
    """``(c, 4, 4)``: base candidates (module docstring), facing the welds' centre."""
    centre = T_flange[:, :3, 3].mean(axis=0)
    if opts.line is not None:
        a, b = (np.asarray(p, dtype=np.float64) for p in opts.line)
        k = max(2, int(math.ceil(np.linalg.norm(b - a) / opts.step)) + 1)
        pts = a + np.linspace(0.0, 1.0, k)[:, None] * (b - a)
        pts = pts[column_free(robot, pts, part)]
    else:
        z = opts.floor_z
        if z is None:
            z = float(part.bounds[0, 2]) if part is not None else 0.0  # type: ignore[attr-defined]
        hw = opts.half_width if opts.half_width is not None else arm_reach(robot) + robot.opw.a1
        g = np.arange(-hw, hw + 1e-9, opts.step)
        X, Y = np.meshgrid(centre[0] + g, centre[1] + g, indexing="ij")
        pts = np.concatenate(
            [np.c_[X.ravel(), Y.ravel(), np.full(X.size, z + h)] for h in opts.heights]
        )
        # the wrist centre must be within the arm's reach of the A2 axis for some weld
        wc = T_flange[:, :3, 3]
        d = np.linalg.norm(wc[None] - (pts + [0.0, 0.0, robot.opw.c1])[:, None], axis=2).min(axis=1)
        pts = pts[d <= arm_reach(robot) + robot.opw.a1 + robot.opw.c4]
        pts = pts[column_free(robot, pts, part, floor=z)]
    pts = pts[opts.outside(pts)]  # robots already placed
    yaws = []
    for p in pts:
        face = math.degrees(math.atan2(centre[1] - p[1], centre[0] - p[0]))
        yaws.extend((p, face + dy) for dy in (0.0, *opts.extra_yaws))
    if not yaws:
        return np.zeros((0, 4, 4))
    return np.array([base_pose(*p, yaw) for p, yaw in yaws])


def column_free(
    robot: Robot, pts: NDArray[np.float64], part: object | None, floor: float | None = None
) -> NDArray[np.bool_]:
    """``(k,) bool``: the capsule about A1 (from ``floor``, default the base itself: a pedestal
    below it, to the A2 axis) of a base at each point is clear of the part (module docstring)."""
    if part is None or len(pts) == 0:
        return np.ones(len(pts), dtype=bool)
    from weldplan.geometry.distance import SurfaceDistance

    radius = 0.0
    for lk in robot.links[:2]:
        radius = max(radius, float(np.linalg.norm(lk.vertices[:, :2], axis=1).max()))
    lo = pts[:, 2] if floor is None else np.minimum(pts[:, 2], floor)
    top = pts[:, 2] + robot.opw.c1
    n_t = max(2, int(math.ceil(float((top - lo).max()) / (radius / 2))) + 1)
    ts = np.linspace(0.0, 1.0, n_t)
    zs = lo[:, None] + ts[None] * (top - lo)[:, None]  # (k, n_t)
    probe = np.concatenate(
        [np.broadcast_to(pts[:, None, :2], (len(pts), n_t, 2)), zs[..., None]], axis=2
    )
    d = SurfaceDistance(part)(probe.reshape(-1, 3)).reshape(len(pts), n_t)
    # points of the column lie within radius + half the probe spacing of a probe
    return d.min(axis=1) > radius + (top - lo) / (n_t - 1) / 2


def search_base(
    robot: Robot,
    T_flange: ArrayLike,
    part: object | None = None,
    opts: BaseSearch | None = None,
    *,
    singular_deg: float = DEFAULT_SINGULAR_DEG,
    top: int = 1,
    alternatives: Sequence[NDArray[np.float64]] | None = None,
) -> list[Placement]:
    """The ``top`` best candidate bases (module docstring): most welds usable, then the largest
    smallest manipulability over them; best first.

    Parameters
    ----------
    robot
        The robot (its own base is ignored).
    T_flange
        ``(n, 4, 4)`` mm: the flange poses at the welds, part frame.
    part
        The part mesh (mm), to keep the base column out of it and for the default floor height.
    opts
        Where to look (:class:`BaseSearch`).
    top
        How many placements to return (fewer when there are fewer candidates).
    alternatives
        Per weld, ``(k, 4, 4)`` mm: its alternative flange poses (the tool's other free poses,
        :mod:`weldplan.robot.placement.altreach`). In the full score a weld whose pose fails at a
        candidate counts there when one of them is usable (the first pass on :data:`SCORE_WELDS`
        welds scores the given poses only).

    Raises
    ------
    PlanningError
        No candidate is clear of the part, or none reaches any weld.
    """
    from weldplan.errors import PlanningError

    opts = opts or BaseSearch()
    if not (opts.step > 0 and math.isfinite(opts.step)):
        raise InputError(
            f"the search step must be a positive number of mm, got {opts.step}", field="step"
        )
    T = np.asarray(T_flange, dtype=np.float64).reshape(-1, 4, 4)
    bases = candidate_bases(robot, T, part, opts)
    if len(bases) == 0:
        raise PlanningError("no base candidate is clear of the part within reach of the welds")
    dist = None
    if part is not None:
        from weldplan.geometry.distance import SurfaceDistance

        dist = SurfaceDistance(part)

    if len(T) > SCORE_WELDS and len(bases) > PRESELECT:
        # a first pass on evenly spread welds keeps the candidates worth scoring on all of them
        sub = T[np.linspace(0, len(T) - 1, SCORE_WELDS).round().astype(np.int64)]
        c_sub, m_sub = _score(robot, sub, bases, singular_deg, dist)
        m_sub = np.round(m_sub, TIE_DECIMALS)
        bases = bases[np.lexsort((-m_sub, -c_sub))[:PRESELECT]]
    counts, mins = _score(robot, T, bases, singular_deg, dist, alternatives)
    mins = np.round(mins, TIE_DECIMALS)  # round-off ties: the candidates' order decides
    if counts.max() == 0:
        raise PlanningError(
            f"no base among {len(bases)} candidates reaches any weld: widen the search"
        )
    order = np.lexsort((-mins, -counts))[: max(1, int(top))]
    order = order[counts[order] > 0]
    best = int(order[0])
    log.info(
        "base search: %d candidates, best reaches %d/%d welds, min manipulability %.4f",
        len(bases),
        counts[best],
        len(T),
        mins[best],
    )
    return [
        Placement(
            base=bases[i],
            n_usable=int(counts[i]),
            n_welds=len(T),
            min_manipulability=float(mins[i]),
            candidates=len(bases),
            searched=True,
        )
        for i in order
    ]


def _score(
    robot: Robot,
    T: NDArray[np.float64],
    bases: NDArray[np.float64],
    singular_deg: float,
    dist: object | None,
    alts: Sequence[NDArray[np.float64]] | None = None,
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """:func:`score_bases` with the chord proxy (:func:`sight_clear`, with ``dist``; reach alone
    when it rules out every candidate) and, with ``alts``, each weld's alternative poses."""

    def more(d: object | None) -> Callable | None:
        if alts is None:
            return None
        return lambda served: alt_reach(robot, bases, alts, ~served, singular_deg, d)

    clear = None if dist is None else sight_clear(robot, bases, T, dist)
    counts, mins = score_bases(robot, T, bases, singular_deg, clear, more(dist))
    if clear is not None and counts.max() == 0:  # the proxy rules all out: reach alone
        counts, mins = score_bases(robot, T, bases, singular_deg, None, more(None))
    return counts, mins


def alt_pairs(
    alts: Sequence[NDArray[np.float64]], need: NDArray[np.bool_]
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """``(cand (p,), weld (p,), T (p, 4, 4))``: every alternative of every needed (candidate,
    weld) pair of ``need (c, n)``, one row each."""
    c_idx, w_idx = np.nonzero(need)
    sizes = np.array([len(alts[w]) for w in w_idx], dtype=np.int64)
    cand = np.repeat(c_idx, sizes)
    weld = np.repeat(w_idx, sizes)
    T = np.concatenate([alts[w] for w in w_idx]) if len(w_idx) else np.zeros((0, 4, 4))
    return cand, weld, T


def alt_reach(
    robot: Robot,
    bases: NDArray[np.float64],
    alts: Sequence[NDArray[np.float64]],
    need: NDArray[np.bool_],
    singular_deg: float,
    dist: object | None = None,
) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Per (candidate base, weld) of ``need (c, n)``: whether one of the weld's alternative
    flange poses (``alts[w] (k, 4, 4)`` mm, part frame) is usable from the base ``bases[c]``
    (with ``dist``, a :class:`~weldplan.geometry.distance.SurfaceDistance`, only where its
    shoulder-wrist chord misses the part: :func:`chord_clear`), and the
    best manipulability over those usable branches (``-inf`` elsewhere)."""
    got = np.zeros(need.shape, dtype=bool)
    best = np.full(need.shape, -np.inf)
    cand, weld, T = alt_pairs(alts, need & np.array([len(a) > 0 for a in alts])[None])
    if len(T) == 0:
        return got, best
    Tb = np.linalg.inv(bases)[cand] @ T  # in each candidate's base frame
    keep = may_reach(robot, Tb)
    if dist is not None:
        keep[keep] = chord_clear(robot, bases[cand[keep]], T[keep], dist)
    cand, weld, Tb = cand[keep], weld[keep], Tb[keep]
    if len(Tb) == 0:
        return got, best
    at_origin = robot.with_base(np.eye(4))
    br = at_origin.ik_all(Tb)
    idx = np.argwhere(usable(br, singular_deg))
    if len(idx) == 0:
        return got, best
    m = at_origin.manipulability(br.q[idx[:, 0], idx[:, 1]])
    np.maximum.at(best, (cand[idx[:, 0]], weld[idx[:, 0]]), m)
    got = np.isfinite(best)
    return got, best
