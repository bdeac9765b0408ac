"""Joint-to-joint local paths: ant colony (+ secondary optimisation) or an exact grid search.

Wang et al., "Welding robot collision-free path optimization", Applied Sciences 7 (2017) 115,
section 4. A local path leaves the real joint ``i`` for its virtual joint (the nearest free voxel
centre), crosses the free grid to the virtual joint of ``j`` and steps onto the real joint ``j``.

Methods (``method=``):

``"so-aco"``
    The ant colony of sections 4.1-4.2 (:func:`weldplan.optim.discrete.aco_grid.ant_colony_grid`),
    then the secondary optimisation of section 4.3 (:func:`secondary_optimization`).
``"aco"``
    The ant colony alone: the shortest 6-connected route the ants found.
``"exact"``
    The baseline: the exact shortest 26-connected lattice path (A*,
    :func:`weldplan.geometry.gridsearch.shortest_grid_path`; by default a diagonal move must
    cross free voxels only, see :class:`LocalParams`), then the same secondary optimisation.

For every method, when the straight segment between the two virtual joints is free at the
clearance, that segment is the path and no search runs (``LocalPath.fast_path``).

The grid is the search space; python-fcl is the judge (DESIGN.md). A lattice move between two free
voxel centres can still graze a sharp edge of the part (both ends at the clearance, the middle a
little closer), so every move of a grid route that stays in the result is checked with the FCL
capsule (for ``"aco"`` all of them; with the secondary optimisation, the moves it keeps without a
shortcut); when one fails, every move of that route is checked at once and each one that fails
is forbidden, and the search runs again (until a route passes, no route is left, or
``max_repairs`` searches, unbounded by default: each repair forbids at least one more move, so
it ends). Every shortcut the secondary optimisation takes is an FCL-checked segment, and a piece of
a checked segment is free, so the path that leaves this module is collision-free at the clearance
between the virtual joints. The two legs real joint -> virtual joint touch the part by
construction (a real joint lies on its surface) and are not checked.

Deviations from the paper, named (each a :class:`LocalParams` field):

- the FCL check of kept lattice moves and the repair search above (``max_repairs``);
- the continuous refinement above (``refine``, off unless asked for);
- the colony searches a box around the pair (``crop_margin``, 50 mm); when the box does not
  connect the pair its margin grows (``crop_growth``, x2 each time) until it does, never past
  ``max_search_voxels`` voxels (then :class:`SearchLimitError`, a :class:`PlanningError` naming
  the pair); the exact search runs on the whole grid when the grid is within that cap, else on
  the same growing boxes (then it is exact within the box only);
- the exact baseline forbids corner cutting by default (``corner_cutting``);
- the secondary optimisation stops after ``max_so_passes`` passes (a guard; it converges first).

Optional continuous refinement (``LocalParams.refine``, weldplan's own stage, not the paper's):
the path between the virtual joints goes through :func:`weldplan.weld.refine.refine_path`
(shortcuts anywhere on the path, vertices slid to the clearance; python-fcl has the last word).
Off in :class:`LocalParams` so that the paper's pipeline and ``weldplan bench local`` stay as
printed; on in the planning pipeline's defaults (``weldplan plan --no-refine`` turns it off).

The second-class stage (``LocalParams.second_class``, on whenever the exact planner refines;
weldplan's own, :mod:`weldplan.weld.homotopy`): A* runs a second time outside the corridor of
the first route (``class_radius``, at most ``CLASS_EXPANSIONS`` expansions), the same FCL checks,
repairs and secondary optimisation; when that grid path is no longer than the first's
(``class_slack``) it is refined under the same ``refine_budget`` and the shorter refined path is
kept (``LocalPath.classes``, ``LocalPath.second_class``). It catches an obstacle passed on the
side that is shorter on the lattice but longer in space. It is skipped when the first refined
path is within ``CLASS_GAIN`` (0.1 %) of the straight segment, the lower bound of every class.

Lengths: ``LocalPath.inner_length`` is measured between the virtual joints, like the paper's
Table 3 (the paper ignores the legs); ``LocalPath.length`` includes the legs.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, TypedDict, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import PlanningError
from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.grid import ObstacleGrid
from weldplan.geometry.gridsearch import PaddedGrid, shortest_grid_path
from weldplan.optim.discrete.aco_grid import AntColonyParams, ant_colony_grid
from weldplan.options import laid_over
from weldplan.random import RNGLike, as_generator, seed_of
from weldplan.weld.homotopy import CLASS_GAIN
from weldplan.weld.localpath import (
    MAX_SEARCH_VOXELS,
    METHODS,
    LocalParams,
    LocalPath,
    LocalSearchSettings,
    SearchLimitError,
)
from weldplan.weld.searchbox import _connected, _search_grid
from weldplan.weld.secondary import SecondaryResult, polyline_length, secondary_optimization

log = logging.getLogger(__name__)

__all__ = [
    "MAX_SEARCH_VOXELS",
    "METHODS",
    "LocalParams",
    "LocalPath",
    "LocalSearchSettings",
    "SearchLimitError",
    "SecondaryResult",
    "plan_local_path",
    "plan_pair",
    "polyline_length",
    "secondary_optimization",
]


def _assemble(
    start_xyz: NDArray[np.float64], inner: NDArray[np.float64], goal_xyz: NDArray[np.float64]
) -> NDArray[np.float64]:
    parts = []
    if np.linalg.norm(inner[0] - start_xyz) > 1e-9:
        parts.append(start_xyz[None])
    parts.append(inner)
    if np.linalg.norm(inner[-1] - goal_xyz) > 1e-9:
        parts.append(goal_xyz[None])
    return np.concatenate(parts)


_FCL_EDGE = "a segment inside a checked segment failed the FCL check (numerical edge case)"


def _bad_moves(P: NDArray[np.float64], segs_free: Callable[..., NDArray[np.bool_]]) -> list[int]:
    """Indices ``k`` of the segments ``P[k] -> P[k + 1]`` that fail the check (one batch)."""
    return [int(k) for k in np.flatnonzero(~segs_free(P[:-1], P[1:]))]


class _Checks:
    """The FCL capsule checks of one pair at the clearance, counted."""

    def __init__(self, collision: CollisionModel, radius: float) -> None:
        self.collision = collision
        self.radius = radius
        self.n = 0

    def one(self, a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
        # one fcl capsule query (~16 us); the sphere-traced batch check pays off only for many
        # segments at once, and the secondary optimisation asks one segment at a time
        self.n += 1
        return bool(self.collision.segments_free(a[None], b[None], self.radius, method="fcl")[0])

    def many(self, A: NDArray[np.float64], B: NDArray[np.float64], radius: float | None = None):
        self.n += len(A)
        r = self.radius if radius is None else radius
        return self.collision.segments_free(A, B, r, method="fcl")


@dataclass(frozen=True)
class _Search:
    """One pair's search, as :func:`plan_local_path` set it up: the grid and the padded search
    box ``pg`` (its ``origin`` in the grid's indices), the virtual joints ``s`` and ``g`` (grid
    indices), the settings, the FCL checks (counted), the colony's generator and the deadline
    (``time.perf_counter()``, ``None``: none)."""

    grid: ObstacleGrid
    pg: PaddedGrid
    origin: NDArray[np.int64]
    s: NDArray[np.int64]
    g: NDArray[np.int64]
    prm: LocalParams
    checks: _Checks
    gen: np.random.Generator
    deadline: float | None


def _grid_route(
    sr: _Search,
    method: str,
    callback: Callable[[int, float], None] | None,
    stats: dict[str, Any],
    forbidden: NDArray[np.int64] | None = None,
    max_expansions: int | None = None,
) -> tuple[NDArray[np.float64] | None, float, int, str, NDArray[np.int64] | None]:
    """Search, check the route with FCL, forbid the moves that graze, search again.

    Returns ``(inner points or None, raw grid length, SO passes, reason, lattice route)`` (the
    route in ``pg``'s indices) and fills ``stats`` (``iterations``, ``ants``, ``evaluations``,
    ``history``, ``repairs``). ``forbidden``: padded flat indices the exact search must not
    enter (:func:`weldplan.weld.homotopy.corridor`); ``max_expansions``: its cap a search.

    A route fails when a lattice move between two free voxel centres grazes a sharp edge. Every
    move of a failing route is checked in one batch and every grazing one is forbidden (both
    directions): forbidding only the first one, as before, let a route that runs along a long
    sheet edge graze again at the next move, and three repairs were not enough.
    """
    grid, pg, origin, s, g, prm = sr.grid, sr.pg, sr.origin, sr.s, sr.g, sr.prm
    checks, gen, deadline = sr.checks, sr.gen, sr.deadline
    conn = 6 if method != "exact" else prm.connectivity
    blocked: set[tuple[int, int]] = set()
    limit = math.inf if prm.max_repairs is None else prm.max_repairs
    repairs = 0
    while True:
        if method == "exact":
            r = shortest_grid_path(
                pg, s - origin, g - origin, connectivity=conn, pitch=grid.pitch,
                blocked_edges=blocked, deadline=deadline, corner_cutting=prm.corner_cutting,
                forbidden=forbidden, max_expansions=max_expansions,
            )  # fmt: skip
            stats["evaluations"] += r.expansions
        else:
            r = ant_colony_grid(
                pg, s - origin, g - origin, params=prm.colony, pitch=grid.pitch, rng=gen,
                deadline=deadline, blocked_edges=blocked, callback=callback,
            )  # fmt: skip
            stats["iterations"] += r.iterations
            stats["ants"] += r.ants
            stats["evaluations"] += r.ants
            stats["history"] = stats["history"] + r.best_history
        stats["repairs"] = repairs
        if not r.success:
            return None, math.inf, 0, r.reason, None
        P = grid.index_to_world(r.path + origin)
        if method == "aco":
            bad = _bad_moves(P, checks.many)
            so = None
        else:
            so = secondary_optimization(
                P, checks.one, step=prm.so_step or grid.pitch, max_passes=prm.max_so_passes,
                deadline=deadline, check_adjacent=True,
            )  # fmt: skip
            bad = [] if so.bad_segment is None else _bad_moves(P, checks.many) or [-1]
        if not bad:
            if so is None:
                return P, r.length, 0, "", r.path
            return so.points, r.length, so.passes, "", r.path
        if bad == [-1]:
            return None, math.inf, 0, _FCL_EDGE, None
        if repairs >= limit:
            return (
                None,
                math.inf,
                0,
                (f"grid routes kept grazing the part after {prm.max_repairs} repairs"),
                None,
            )
        flat = pg.flat(r.path)
        blocked.update((int(flat[k]), int(flat[k + 1])) for k in bad)
        repairs += 1
        log.debug("%d lattice move(s) graze the part at the clearance; searching again", len(bad))


def _refine_inner(
    inner: NDArray[np.float64],
    collision: CollisionModel,
    checks: _Checks,
    clearance: float,
    prm: LocalParams,
    stats: dict[str, Any],
) -> tuple[NDArray[np.float64], bool]:
    """:func:`weldplan.weld.refine.refine_path` on the path between the virtual joints, its
    checks and final check through python-fcl (counted in ``checks``); a spent CPU cap is
    counted in ``stats["refine_clock_stops"]``."""
    from weldplan.weld.refine import RefineSettings, refine_path

    rp = refine_path(
        inner, collision, clearance,
        RefineSettings(taut=prm.refine_taut, time_budget=prm.refine_budget),
        check=lambda A, B, rad: checks.many(A, B, rad),
        final_check=lambda A, B, rad: checks.many(A, B, rad),
    )  # fmt: skip
    if not rp.refined:
        log.debug("refinement kept the grid path: %s", rp.status)
    stats["refine_clock_stops"] = stats.get("refine_clock_stops", 0) + int(rp.clock_stopped)
    return np.asarray(rp.points), rp.refined


class LocalSearchOptions(TypedDict, total=False):
    """The keyword conveniences of :func:`plan_local_path`: the fields of
    :class:`~weldplan.weld.localpath.LocalSearchSettings` by name."""

    method: str
    params: LocalParams | AntColonyParams | Mapping[str, Any] | None
    time_budget: float | None


def plan_local_path(
    grid: ObstacleGrid,
    collision: CollisionModel,
    start_xyz: ArrayLike,
    goal_xyz: ArrayLike,
    start_idx: ArrayLike,
    goal_idx: ArrayLike,
    settings: LocalSearchSettings | None = None,
    *,
    rng: RNGLike = None,
    callback: Callable[[int, float], None] | None = None,
    **options: Unpack[LocalSearchOptions],
) -> LocalPath:
    """Plan the local path from a real joint to another through their virtual joints.

    Parameters
    ----------
    grid
        The obstacle grid (its ``clearance`` is the radius of the FCL checks).
    collision
        The FCL model of the part.
    start_xyz, goal_xyz
        ``(3,)`` real joints (mm).
    start_idx, goal_idx
        ``(3,) int`` grid indices of their virtual joints (free voxels).
    settings
        The method (``"so-aco"`` by default, ``"aco"`` or ``"exact"``), the planners'
        :class:`LocalParams` (``refine=True`` adds the continuous refinement, module docstring)
        and the time budget: :class:`~weldplan.weld.localpath.LocalSearchSettings`; ``None``:
        the defaults.
    rng
        Seed or generator (the colony's only source of randomness).
    callback
        ``callback(iteration, best_length)`` after each colony iteration.
    **options
        ``method=``, ``params=`` and ``time_budget=``, laid over ``settings`` (the keywords of
        this function before the settings object existed).

    Returns
    -------
    LocalPath
        ``success=False`` with the reason when the goal cannot be reached (enclosed, cut off by
        the region of interest) or time ran out; never a path that collides.

    Raises
    ------
    PlanningError
        When a virtual joint lies outside the grid or on an obstacle voxel.
    SearchLimitError
        A :class:`PlanningError`: no search box within ``max_search_voxels`` connects the pair
        (:class:`LocalParams`); the pipeline records the pair as unreachable.
    ValueError
        For an unknown method or parameter (a :class:`~weldplan.errors.ConfigError` naming the
        field for a bad setting).
    TypeError
        For a keyword that is not a setting.
    """
    t0 = time.perf_counter()
    c0 = time.process_time()
    search = laid_over(LocalSearchSettings, settings, options, "plan_local_path")
    method, prm, time_budget = search.method, search.params, search.time_budget
    seed = seed_of(rng)
    gen = as_generator(rng)
    deadline = None if time_budget is None else t0 + float(time_budget)
    start_xyz = np.asarray(start_xyz, dtype=np.float64).reshape(3)
    goal_xyz = np.asarray(goal_xyz, dtype=np.float64).reshape(3)
    s = np.asarray(start_idx, dtype=np.int64).reshape(3)
    g = np.asarray(goal_idx, dtype=np.int64).reshape(3)
    for name, idx in (("start", s), ("goal", g)):
        if not grid.contains(idx):
            raise PlanningError(
                f"{name} virtual joint {idx.tolist()} lies outside the grid {grid.shape} "
                "(is the region of interest too small?)"
            )
        if not grid.is_free(idx):
            raise PlanningError(f"{name} virtual joint {idx.tolist()} is not a free voxel")
    vs = grid.index_to_world(s)
    vg = grid.index_to_world(g)
    checks = _Checks(collision, grid.clearance)

    def done(**kw: Any) -> LocalPath:
        kw.setdefault("points", np.zeros((0, 3)))
        pts = kw["points"]
        success = kw.setdefault("success", len(pts) > 0)
        kw.setdefault("length", polyline_length(pts) if success else math.inf)
        return LocalPath(
            method=method,
            seed=seed,
            collision_checks=checks.n,
            seconds=time.perf_counter() - t0,
            cpu_seconds=time.process_time() - c0,
            **kw,
        )

    # fast path: the straight segment between the virtual joints is free
    if np.array_equal(s, g) or checks.one(vs, vg):
        inner = vs[None] if np.array_equal(s, g) else np.stack([vs, vg])
        d = polyline_length(inner)
        return done(
            points=_assemble(start_xyz, inner, goal_xyz),
            inner_length=d,
            raw_length=d,
            fast_path=True,
            reason="straight segment free",
        )

    # diagonal moves without corner cutting reach exactly the 6-connected region
    label_conn = 6 if method != "exact" or not prm.corner_cutting else prm.connectivity
    if not _connected(grid, s, g, label_conn):
        return done(
            inner_length=math.inf,
            reason=f"goal not reachable from start: different {label_conn}-connected free "
            "regions (enclosed, or cut off by the region of interest)",
        )

    pg, origin, search_voxels, search_boxes = _search_grid(grid, s, g, method, prm, label_conn)
    stats: dict[str, Any] = {"iterations": 0, "ants": 0, "evaluations": 0, "history": ()}
    stats.update(search_voxels=search_voxels, search_boxes=search_boxes, repairs=0)
    sr = _Search(grid, pg, origin, s, g, prm, checks, gen, deadline)
    inner, raw_len, so_passes, reason, route = _grid_route(sr, method, callback, stats)
    if inner is None:
        return done(inner_length=math.inf, reason=reason, **stats)
    so_length = polyline_length(inner)
    refined = False
    classes, second = 1, False
    if prm.refine:
        inner, refined = _refine_inner(inner, collision, checks, grid.clearance, prm, stats)
        # no path is shorter than the straight segment: when the refined path is within
        # CLASS_GAIN of it, another class cannot gain more than that and is not searched
        near = polyline_length(inner) <= (1.0 + CLASS_GAIN) * float(np.linalg.norm(vg - vs))
        if prm.second_class and method == "exact" and route is not None and not near:
            alt = _second_class(sr, route, so_length, polyline_length(inner), stats)
            if alt is not None:
                classes = 2
                if alt[0] is not None:
                    inner, raw_len, so_length, so_passes, refined = alt
                    second = True
    return done(
        points=_assemble(start_xyz, inner, goal_xyz),
        inner_length=polyline_length(inner),
        raw_length=raw_len,
        so_length=so_length,
        refined=refined,
        so_passes=so_passes,
        classes=classes,
        second_class=second,
        **stats,
    )


def _second_class(
    sr: _Search,
    route: NDArray[np.int64],
    so_first: float,
    best: float,
    stats: dict[str, Any],
) -> tuple[Any, ...] | None:
    """The second-class stage (:mod:`weldplan.weld.homotopy`): A* outside the first route's
    corridor, the same FCL checks and secondary optimisation, refined under the same cap when
    the trigger fires.

    Returns ``None`` when no candidate was refined; ``(None,)`` when one was and the first path
    stays shorter; else ``(inner, raw length, SO length, SO passes, refined)`` of the candidate.
    Adds the search's expansions and repairs to ``stats``.
    """
    from weldplan.weld.homotopy import CLASS_EXPANSIONS, corridor, second_class_wins

    grid, prm, checks = sr.grid, sr.prm, sr.checks
    ban = corridor(sr.pg, route, prm.class_radius, grid.pitch)
    if len(ban) == 0:
        return None
    st: dict[str, Any] = {"iterations": 0, "ants": 0, "evaluations": 0, "history": ()}
    cap = CLASS_EXPANSIONS[0] * stats["evaluations"] + CLASS_EXPANSIONS[1]
    inner, raw, passes, reason, _ = _grid_route(
        sr, "exact", None, st, forbidden=ban, max_expansions=cap
    )
    stats["evaluations"] += st["evaluations"]
    stats["repairs"] += st.get("repairs", 0)
    if inner is None:
        log.debug("no second-class route: %s", reason)
        return None
    so = polyline_length(inner)
    if not second_class_wins(so_first, so, prm.class_slack):
        return None
    inner, refined = _refine_inner(inner, collision=checks.collision, checks=checks,
                                   clearance=grid.clearance, prm=prm, stats=stats)  # fmt: skip
    length = polyline_length(inner)
    log.debug("second class: %.3f mm (first %.3f mm)", length, best)
    if not length < best - 1e-6:
        return (None,)
    return inner, raw, so, passes, refined


def plan_pair(
    cell: Any,
    i: int,
    j: int,
    *,
    method: str = "so-aco",
    params: LocalParams | AntColonyParams | Mapping[str, Any] | None = None,
    rng: RNGLike = None,
    time_budget: float | None = None,
    callback: Callable[[int, float], None] | None = None,
) -> LocalPath:
    """Local path from joint position ``i`` to joint position ``j`` (0..n-1) of a cell.

    ``cell`` is a :class:`weldplan.weld.cell.Cell` (anything with ``.grid``, ``.collision``,
    ``.joints.xyz (n, 3)`` and ``.virtual_index (n, 3)``). See :func:`plan_local_path`.
    """
    xyz = np.asarray(cell.joints.xyz, dtype=np.float64)
    vidx = np.asarray(cell.virtual_index, dtype=np.int64)
    n = len(xyz)
    for name, k in (("i", i), ("j", j)):
        if not 0 <= int(k) < n:
            raise IndexError(f"joint position {name}={k} out of range 0..{n - 1}")
    try:
        settings = LocalSearchSettings(method, LocalParams.coerce(params), time_budget)
        return plan_local_path(
            cell.grid, cell.collision, xyz[i], xyz[j], vidx[i], vidx[j], settings,
            rng=rng, callback=callback,
        )  # fmt: skip
    except SearchLimitError as exc:
        ids = getattr(getattr(cell, "joints", None), "ids", None)
        name = f"{ids[i]} -> {ids[j]}" if ids is not None else f"{i} -> {j}"
        raise SearchLimitError(f"joints {name}: {exc}", voxels=exc.voxels, cap=exc.cap) from exc
