"""Continuous refinement of a collision-free polyline: shortcuts anywhere on the path, then the
vertices slide toward the clearance surface (issue 15, items 1 and 3).

A grid planner (SO-ACO, exact A* + the secondary optimisation of Wang et al. 2017, section 4.3)
leaves a path whose vertices are grid points or points of split grid segments; the shortest path at
the clearance grazes edges at exactly the clearance through voxels the grid marks blocked, and no
grid point lies there. :func:`refine_path` takes such a path off the grid in two stages, in R^d,
against any :class:`~weldplan.geometry.pathcore.PathObstacle` (the 3D FCL body, a 2D map):

1. **Continuous shortcut** (:func:`shortcut_path`): from the current point, the farthest vertex of
   the path it sees in a straight line (a batch of segment checks), then the farthest point *on the
   next segment* it sees (a search on the segment's parameter), which becomes the next vertex. The
   secondary optimisation only tries grid points; here a vertex may land anywhere on the path.
2. **Vertex optimisation**, by default all vertices at once (:func:`weldplan.weld.taut.tauten_path`:
   the shortest polyline under separating planes through the contact points, a second-order cone
   program a round, trust region, every round judged by the check), with ``taut=False`` one
   vertex at a time (:func:`tighten_path`, below). The joint program is what reaches the
   optimum on curved surfaces, where a vertex held on both of its segments must slide along the
   surface (its lengths against OMPL BIT* 10 s: docs/bench-local-peers.md).

   :func:`tighten_path`: the shortest path subject to "every segment is
   free at the clearance" is a taut string. Each interior vertex ``v`` between its neighbours
   ``a`` and ``b`` moves toward the point of the chord ``ab`` nearest to it, or toward the chord's
   middle, by the largest of the steps ``1, 1/2, 1/4, ...`` (:data:`STEPS`) that keeps both of
   its segments free, whichever shortens ``|av| + |vb|`` more (odd and even vertices in turn, so
   neighbours do not move together; every candidate of a half-sweep is checked in one batch).
   ``|a v(t)| + |v(t) b|`` is convex in ``t`` and least at ``t = 1``, so the length never grows. A
   vertex that reaches its chord is dropped. When a sweep gains less than ``tol``, every segment
   that passes near the obstacle gets a vertex at its point of closest approach (distance
   queries, :func:`_split_contacts`: the string can then pivot about the contact and wrap around
   rounded edges) and the sweeps go on, ``levels`` times. A vertex stops where a segment
   touches the clearance: the path touches the clearance where the optimum does.

   Moving toward the chord alone jams: a vertex held up by a segment that touches the clearance
   cannot come down that way. Sliding the vertex along its own segment (toward a neighbour)
   cuts the corner instead, and the contact splits let the string wrap: on a 100 mm cube a path
   over the top ends within 0.2 % of the exact optimum (three levels), and around a disc in 2D
   within 0.5 % (tests/test_refine.py, tests/test_pathcore.py).

Every new segment is checked at ``clearance + margin`` (:data:`REFINE_MARGIN`, 0.01 mm), so the
result cannot sit on the edge of the independent check by rounding; segments kept from the input
are the input's own (checked by the planner at the clearance). The result is re-checked at the
clearance with ``final_check`` (the planner passes python-fcl: the same judge as
:func:`weldplan.weld.verify.verify_route`); if any segment fails, the input comes back unchanged
with the reason in ``status``: nothing leaves this function unchecked.

This stage is weldplan's own: it is not in Wang et al. 2017 (the paper ends with its section 4.3
secondary optimisation), so the paper's pipeline runs without it (``LocalParams.refine=False``,
``weldplan plan --no-refine``).
"""

from __future__ import annotations

import json
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, TypedDict, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, InputError
from weldplan.geometry.pathcore import PathObstacle, as_path, polyline_length
from weldplan.options import laid_over

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
SegmentsCheck = Callable[[FloatArray, FloatArray, float], NDArray[np.bool_]]

__all__ = [
    "REFINE_MARGIN",
    "STEPS",
    "RefinedPath",
    "refine_path",
    "shortcut_path",
    "tighten_path",
]

#: mm (map units in 2D) added to the clearance for every segment the refinement creates, so that a
#: segment touching the clearance is not decided by the rounding of the independent check
REFINE_MARGIN = 0.01
#: the fractions of the move toward the chord a vertex tries, largest first
STEPS = (1.0, 0.5, 0.25, 0.125)
#: bisection steps after the largest free step of :data:`STEPS`
BISECT = 3
#: parameter grid and bisection depth of the search along one segment in the continuous shortcut
_T_GRID = 8
_T_BISECT = 6
#: sweeps per level of the vertex optimisation (a guard; it converges first)
MAX_SWEEPS = 60
#: levels of contact splitting of the vertex optimisation: one level gave the same mean length
#: as three on the demo's blocked pairs (0.9966 of the exact planner's) at a fifth of the checks;
#: wrapping a rounded edge closely needs more (a 100 mm cube: 0.6 % over with one, 0.13 % with
#: three)
LEVELS = 1
#: samples per segment searched for its point of closest approach between levels
CONTACT_SAMPLES = 32
#: a segment within ``radius * (1 + CONTACT_BAND)`` of the obstacle gets a vertex there
CONTACT_BAND = 1.0
#: a vertex whose two segments are longer than its chord by less than this (mm) does not move
_STRAIGHT_GAIN = 1e-9
#: a vertex this close to its chord (relative to the coordinates' size) lies on it
_COLLINEAR = 1e-12
#: a sweep that shortens the path by less than this (mm) ends a level
TOL = 1e-3


@dataclass(frozen=True, eq=False)
class RefinedPath:
    """The outcome of :func:`refine_path`.

    Attributes
    ----------
    points
        ``(n, d) float`` the refined path (mm in 3D), same first and last point as the input.
    length
        Its length.
    input_length
        Length of the input.
    shortcut_length
        Length after the continuous shortcut, before the vertex optimisation.
    checks
        Segments checked (every segment of every batch, the final check included).
    sweeps
        Half-sweeps (``taut=False``) or rounds (``taut=True``) of the vertex optimisation.
    seconds
        Wall time.
    refined
        False when the input came back unchanged (see ``status``).
    status
        One line: what happened.
    clock_stopped
        The CPU-time cap (``time_budget``) was spent when the vertex optimisation ended: it
        may have stopped it, so the path may depend on the machine's speed and load (a safety
        net the caller reports; the work bounds are the rounds and sweeps).
    """

    points: FloatArray
    length: float
    input_length: float
    shortcut_length: float
    checks: int
    sweeps: int
    seconds: float
    refined: bool
    status: str
    clock_stopped: bool = False

    def __post_init__(self) -> None:
        pts = np.array(self.points, dtype=np.float64)
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)

    @property
    def gain(self) -> float:
        """``input_length - length`` (>= 0)."""
        return self.input_length - self.length

    def to_dict(self) -> dict[str, Any]:
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["points"] = self.points.tolist()
        return d

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RefinedPath:
        kw = dict(d)
        kw["points"] = np.asarray(kw["points"], dtype=np.float64)
        return cls(**kw)


class _Counter:
    """``obstacle.segments_free`` at a fixed radius, counting the segments it is asked about."""

    def __init__(self, check: SegmentsCheck, radius: float) -> None:
        self.check = check
        self.radius = float(radius)
        self.n = 0

    def __call__(self, A: FloatArray, B: FloatArray) -> NDArray[np.bool_]:
        self.n += len(A)
        if len(A) == 0:
            return np.zeros(0, dtype=bool)
        return np.asarray(self.check(A, B, self.radius), dtype=bool)


def _farthest_on_segment(
    free: _Counter, p: FloatArray, a: FloatArray, b: FloatArray
) -> tuple[float, FloatArray]:
    """Largest ``t`` in ``[0, 1)`` found such that ``p -> a + t (b - a)`` is free (0: none)."""
    ts = np.arange(1, _T_GRID, dtype=np.float64) / _T_GRID
    Q = a + ts[:, None] * (b - a)
    ok = free(np.repeat(p[None], len(Q), axis=0), Q)
    lo = float(ts[np.flatnonzero(ok)[-1]]) if ok.any() else 0.0
    hi = min(1.0, lo + 1.0 / _T_GRID)
    for _ in range(_T_BISECT):
        mid = 0.5 * (lo + hi)
        if free((p)[None], (a + mid * (b - a))[None])[0]:
            lo = mid
        else:
            hi = mid
    return lo, a + lo * (b - a)


def shortcut_path(points: ArrayLike, free: _Counter) -> FloatArray:
    """Stage 1 of :func:`refine_path`: continuous shortcuts (module docstring).

    ``points (n, d)`` must be joined by free segments; the result's vertices lie on the input
    path and its segments are either checked by ``free`` or pieces of input segments.
    """
    P = as_path(points)
    n = len(P)
    if n <= 2:
        return P.copy()
    out = [P[0]]
    cur, k = P[0], 0  # cur lies on segment k -> k + 1 (at its start when cur is P[k])
    while k < n - 1:
        cand = P[k + 1 :]
        ok = free(np.repeat(cur[None], len(cand), axis=0), cand)
        ok[0] = True  # the rest of the current input segment
        j = k + 1 + int(np.flatnonzero(ok)[-1])
        if j == n - 1:
            out.append(P[-1])
            break
        t, q = _farthest_on_segment(free, cur, P[j], P[j + 1])
        out.append(q if t > 0.0 else P[j])
        cur, k = (q, j) if t > 0.0 else (P[j], j)
    return np.asarray(out)


def _half_sweep(P: FloatArray, parity: int, free: _Counter) -> tuple[FloatArray, NDArray]:
    """Move the interior vertices ``parity, parity + 2, ...`` (1: odd, 2: even) toward their
    chords; return the new path and the mask of vertices that reached their chord (droppable).

    Each vertex tries the foot of its perpendicular on the chord, the chord's middle and its two
    neighbours (sliding along one of its own segments cuts the corner: the other segment gets
    shorter and stays a piece of a free one) at the steps :data:`STEPS` (largest first, every
    vertex of the half-sweep in one batch), keeps the shortest free candidate of the largest
    step that has one, then bisects the step between it and the next larger one
    (:data:`BISECT`, toward the target it chose).
    """
    idx = np.arange(parity, len(P) - 1, 2)
    drop = np.zeros(len(P), dtype=bool)
    if len(idx) == 0:
        return P, drop
    n = len(idx)
    a, v, b = P[idx - 1], P[idx], P[idx + 1]
    ab = b - a
    L2 = np.einsum("ij,ij->i", ab, ab)
    s = np.divide(np.einsum("ij,ij->i", v - a, ab), L2, out=np.zeros(n), where=L2 > 0)
    # the foot of the perpendicular on the chord, the chord's middle, and the two neighbours
    # (sliding along its own segment: one new segment, the other a piece of the old one)
    targets = np.stack([a + np.clip(s, 0.0, 1.0)[:, None] * ab, 0.5 * (a + b), a, b])

    def local(C: FloatArray, rows: NDArray) -> FloatArray:
        return np.linalg.norm(C - a[rows], axis=-1) + np.linalg.norm(b[rows] - C, axis=-1)

    def feasible(C: FloatArray, rows: NDArray) -> NDArray[np.bool_]:
        ok = free(np.concatenate([a[rows], C]), np.concatenate([C, b[rows]]))
        return ok[: len(rows)] & ok[len(rows) :]

    t_ok = np.zeros(n)  # the largest step found free (0: none)
    pick = np.zeros(n, dtype=np.int64)  # its target
    # a vertex already on its chord gains nothing by moving: left where it is (a contact point
    # inserted by _split_contacts, which the neighbours pivot about)
    pending = local(v, np.arange(n)) - np.sqrt(L2) > _STRAIGHT_GAIN
    for t in STEPS:
        rows = np.flatnonzero(pending)
        if len(rows) == 0:
            break
        C = v[rows] + t * (targets[:, rows] - v[rows])  # (2, m, d)
        nt = len(targets)
        ok = feasible(C.reshape(-1, P.shape[1]), np.tile(rows, nt)).reshape(nt, -1)
        Lc = np.where(ok, local(C, rows), np.inf)
        k = np.argmin(Lc, axis=0)
        found = np.isfinite(Lc[k, np.arange(len(rows))])
        t_ok[rows[found]] = t
        pick[rows[found]] = k[found]
        pending[rows[found]] = False
    # bisect between the step found and the next larger one
    moved = np.flatnonzero((t_ok > 0) & (t_ok < 1.0))
    lo, hi = t_ok[moved], np.minimum(2.0 * t_ok[moved], 1.0)
    T = targets[pick[moved], moved]
    for _ in range(BISECT):
        if len(moved) == 0:
            break
        mid = 0.5 * (lo + hi)
        ok = feasible(v[moved] + mid[:, None] * (T - v[moved]), moved)
        lo = np.where(ok, mid, lo)
        hi = np.where(ok, hi, mid)
    t_ok[moved] = lo
    go = np.flatnonzero(t_ok > 0)
    Q = P.copy()
    Q[idx[go]] = v[go] + t_ok[go, None] * (targets[pick[go], go] - v[go])
    # on the chord (its two segments are one) or on a neighbour (a zero-length segment)
    drop[idx[go[t_ok[go] == 1.0]]] = True
    return Q, drop


def _split_contacts(
    P: FloatArray, distance: Callable[[FloatArray], FloatArray], radius: float
) -> FloatArray:
    """Insert into every segment that passes within ``radius * (1 + CONTACT_BAND)`` of the
    obstacle its point of closest approach (of :data:`CONTACT_SAMPLES` evenly spaced samples).

    The new vertices lie on the path's own segments (the path does not change); they let the
    sweeps rotate a segment about the point where it touches the clearance instead of pushing its
    far end against it, and let the string wrap around rounded edges.
    """
    if len(P) < 2:
        return P
    t = (np.arange(CONTACT_SAMPLES) + 0.5) / CONTACT_SAMPLES
    S = P[:-1, None, :] + t[None, :, None] * (P[1:] - P[:-1])[:, None, :]
    d = np.asarray(distance(S.reshape(-1, P.shape[1])), dtype=np.float64).reshape(len(P) - 1, -1)
    k = np.argmin(d, axis=1)
    near = d[np.arange(len(k)), k] < radius * (1.0 + CONTACT_BAND)
    out = [P[:1]]
    for i in range(len(P) - 1):
        if near[i]:
            out.append(S[i, k[i]][None])
        out.append(P[i + 1][None])
    return np.concatenate(out)


def tighten_path(
    points: ArrayLike,
    free: _Counter,
    distance: Callable[[FloatArray], FloatArray],
    *,
    levels: int = LEVELS,
    max_sweeps: int = MAX_SWEEPS,
    tol: float = TOL,
    deadline: float | None = None,
) -> tuple[FloatArray, int]:
    """Stage 2 of :func:`refine_path`: the vertex optimisation (module docstring).

    Returns the path and the number of half-sweeps run.
    """
    P = as_path(points).copy()
    sweeps = 0
    for level in range(levels + 1):
        for _ in range(max_sweeps):
            before = polyline_length(P)
            for parity in (1, 2):
                P, drop = _half_sweep(P, parity, free)
                sweeps += 1
                if drop.any():
                    P = P[~drop]
            if before - polyline_length(P) < tol:
                break
            if deadline is not None and time.thread_time() > deadline:
                return P, sweeps
        if level == levels:
            break
        P = _split_contacts(P, distance, free.radius)
    return _drop_straight(P), sweeps


def _drop_straight(P: FloatArray) -> FloatArray:
    """Drop the interior vertices that lie on the chord of their neighbours (to rounding): the
    chord lies within rounding of their two segments, far inside the margin (the final check
    has the last word)."""
    keep = np.ones(len(P), dtype=bool)
    scale = 1.0 + float(np.abs(P).max())
    for i in range(1, len(P) - 1):
        a = P[max(j for j in range(i) if keep[j])]
        v, b = P[i], P[i + 1]
        ab = b - a
        L2 = float(ab @ ab)
        s = 0.0 if L2 == 0 else min(1.0, max(0.0, float((v - a) @ ab) / L2))
        if np.linalg.norm(v - (a + s * ab)) <= _COLLINEAR * scale:
            keep[i] = False
    return P[keep]


@dataclass(frozen=True)
class RefineSettings:
    """How :func:`refine_path` refines, validated once (a ConfigError naming the field).

    Attributes
    ----------
    margin
        mm added to the clearance for every segment the refinement creates
        (:data:`REFINE_MARGIN`).
    levels, max_sweeps, tol
        Midpoint-splitting levels, sweeps per level and the gain (mm) under which a level ends
        (the one-vertex sweeps, ``taut=False``).
    time_budget
        CPU seconds of the calling thread (:func:`time.thread_time`) for the vertex optimisation
        (it stops between sweeps or rounds; the result is still checked). Not wall time: other
        work on a loaded machine must not change the path. ``None``: no cap.
    taut
        Stage 2 is the joint vertex optimisation (:func:`weldplan.weld.taut.tauten_path`: every
        vertex at once, by second-order cone programs; the default) instead of the one-vertex
        sweeps of :func:`tighten_path` (``False``: the stage as it was, ``levels`` and
        ``max_sweeps`` apply to it). On the 32 blocked pairs of ``weldplan bench local --peers``
        the program brought the mean length from 1.006 to 0.995 x OMPL BIT* 10 s
        (docs/bench-local-peers.md); the sweeps jam where a vertex should slide along a curved
        surface.
    """

    margin: float = REFINE_MARGIN
    levels: int = LEVELS
    max_sweeps: int = MAX_SWEEPS
    tol: float = TOL
    time_budget: float | None = None
    taut: bool = True

    def __post_init__(self) -> None:
        for name in ("margin", "tol"):
            v = getattr(self, name)
            ok = isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool)
            if not (ok and math.isfinite(v) and v >= 0):
                raise ConfigError(f"{name} must be a finite number >= 0, got {v!r}", field=name)
        for name in ("levels", "max_sweeps"):
            if int(getattr(self, name)) < 0:
                raise ConfigError(f"{name} must be >= 0, got {getattr(self, name)!r}", field=name)


class RefineOptions(TypedDict, total=False):
    """The keyword conveniences of :func:`refine_path`: :class:`RefineSettings` fields."""

    margin: float
    levels: int
    max_sweeps: int
    tol: float
    time_budget: float | None
    taut: bool


def refine_path(
    points: ArrayLike,
    obstacle: PathObstacle,
    clearance: float,
    settings: RefineSettings | None = None,
    *,
    check: SegmentsCheck | None = None,
    final_check: SegmentsCheck | None = None,
    **options: Unpack[RefineOptions],
) -> RefinedPath:
    """Refine a collision-free polyline off the grid (module docstring).

    Parameters
    ----------
    points
        ``(n, d) float`` a path whose consecutive points are joined by segments free at
        ``clearance`` (mm in 3D): the inner path of a local planner, between virtual joints.
    obstacle
        Any :class:`~weldplan.geometry.pathcore.PathObstacle`: a
        :class:`~weldplan.geometry.collision.CollisionModel` (3D) or a
        :class:`~weldplan.geometry.planar_obstacle.PlanarObstacle` (2D).
    clearance
        Radius of the swept ball (the torch-tip radius, mm).
    settings
        :class:`RefineSettings` (margin, levels, sweeps, tolerance, CPU budget, taut); ``None``:
        the defaults.
    check
        ``check(A, B, radius) -> (m,) bool``, the segment check of the refinement; default
        ``obstacle.segments_free``.
    final_check
        ``final_check(A, B, radius) -> (m,) bool``, the check the result must pass at
        ``clearance``; default ``obstacle.segments_free``. The 3D planner passes python-fcl.
    **options
        Any :class:`RefineSettings` field by name (``taut=False``, ``margin=0.05``...), laid
        over ``settings``; an unknown keyword is a ``TypeError``.

    Returns
    -------
    RefinedPath
        Never longer than the input; the input itself (``refined=False``) when it has fewer than
        three points or when the final check rejects the refined path.

    Raises
    ------
    InputError
        A ``ValueError``: points that are not a finite ``(n, d)`` array, or a clearance that is
        not a finite number >= 0.
    ConfigError
        A ``ValueError``: a bad setting (a margin that is not a finite number >= 0...), naming
        it.
    """
    t0 = time.perf_counter()
    st = laid_over(RefineSettings, settings, options, "refine_path")
    margin, time_budget = st.margin, st.time_budget
    try:
        P = as_path(points)
    except ValueError as exc:
        raise InputError(str(exc), field="points") from None
    ok = isinstance(clearance, (int, float, np.floating, np.integer))
    if not (ok and math.isfinite(clearance) and clearance >= 0):
        raise InputError(
            f"clearance must be a finite number >= 0, got {clearance!r}", field="clearance"
        )
    L0 = polyline_length(P)
    free = _Counter(check or obstacle.segments_free, float(clearance) + float(margin))

    stopped = False  # set once the vertex optimisation has run

    def result(Q: FloatArray, Ls: float, sweeps: int, refined: bool, status: str) -> RefinedPath:
        return RefinedPath(
            points=Q, length=polyline_length(Q), input_length=L0, shortcut_length=Ls,
            checks=free.n, sweeps=sweeps, seconds=time.perf_counter() - t0, refined=refined,
            status=status, clock_stopped=stopped,
        )  # fmt: skip

    if len(P) < 3:
        return result(P, L0, 0, False, "nothing to refine (fewer than 3 points)")
    c0 = time.thread_time()
    deadline = None if time_budget is None else c0 + float(time_budget)
    S = shortcut_path(P, free)
    Ls = polyline_length(S)
    if st.taut:
        from weldplan.weld.taut import tauten_path

        left = None if deadline is None else deadline - time.thread_time()
        Q, sweeps = tauten_path(S, obstacle, float(clearance), free, margin=float(margin),
                                time_budget=left)  # fmt: skip
        Q = _drop_straight(Q)
    else:
        Q, sweeps = tighten_path(
            S, free, obstacle.distance, levels=st.levels, max_sweeps=st.max_sweeps, tol=st.tol,
            deadline=deadline,
        )  # fmt: skip
    # the cap is a safety net: say when it was spent (it may have cut the rounds short)
    stopped = deadline is not None and time.thread_time() >= deadline
    if stopped:
        log.info("refinement: the %.3g s CPU cap was spent (%d rounds)", time_budget, sweeps)
    Q[0], Q[-1] = P[0], P[-1]
    check = final_check or obstacle.segments_free
    final = _Counter(check, float(clearance))
    ok = final(Q[:-1], Q[1:])
    free.n += final.n
    if not ok.all():
        k = int(np.flatnonzero(~ok)[0])
        log.warning("refined path rejected by the final check at segment %d: input kept", k)
        return result(
            P, Ls, sweeps, False, f"refined segment {k} failed the final check: input kept"
        )
    if polyline_length(Q) > L0:
        return result(P, Ls, sweeps, False, "refinement did not shorten the path: input kept")
    return result(Q, Ls, sweeps, True, f"{L0:.3f} -> {polyline_length(Q):.3f} (shortcut {Ls:.3f})")


def refine_local_path(
    cell: Any, lp: Any, *, taut: bool = True, time_budget: float | None = None
) -> Any:
    """A :class:`~weldplan.weld.localpath.LocalPath` of ``cell`` with its path between the virtual
    joints refined (python-fcl checks at the cell's clearance); ``lp`` itself when it failed, is
    a fast path or was refined already. For benches that plan first and refine apart (``cell``:
    anything with ``.collision``, ``.clearance`` or ``.grid.clearance``). ``taut`` and
    ``time_budget`` are :func:`refine_path`'s (``None``: the planner's default,
    :data:`weldplan.weld.localpath.REFINE_BUDGET`)."""
    import dataclasses

    from weldplan.weld.localpath import REFINE_BUDGET

    if not lp.success or lp.fast_path or lp.refined or len(lp.points) < 3:
        return lp
    clearance = float(getattr(cell, "clearance", None) or cell.grid.clearance)
    col = cell.collision
    # the legs to the real joints are the first and last segments unless a joint is its own
    # virtual joint; the inner path is what has inner_length
    P = np.asarray(lp.points)
    a, b = 0, len(P)
    for lo in (0, 1):
        for hi in (len(P), len(P) - 1):
            if abs(polyline_length(P[lo:hi]) - lp.inner_length) < 1e-6 * (1 + lp.inner_length):
                a, b = lo, hi
    fcl = lambda A, B, r: col.segments_free(A, B, r, method="fcl")  # noqa: E731
    budget = REFINE_BUDGET if time_budget is None else time_budget
    st = RefineSettings(taut=taut, time_budget=budget)
    rp = refine_path(P[a:b], col, clearance, st, check=fcl, final_check=fcl)
    if not rp.refined:
        return lp
    pts = np.concatenate([P[:a], rp.points, P[b:]])
    return dataclasses.replace(
        lp, points=pts, length=polyline_length(pts), inner_length=rp.length,
        so_length=lp.inner_length, refined=True, seconds=lp.seconds + rp.seconds,
        collision_checks=lp.collision_checks + rp.checks,
    )  # fmt: skip
