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
shortcut); a move that fails is forbidden and the search runs again (at most ``max_repairs``
times). Every shortcut the secondary optimisation takes is an FCL-checked segment, and a piece of
a checked segment is free, so the path that leaves this module is collision-free at the clearance
between the virtual joints. The two legs real joint -> virtual joint touch the part by
construction (a real joint lies on its surface) and are not checked.

Deviations from the paper, named (each a :class:`LocalParams` field):

- the FCL check of kept lattice moves and the repair search above (``max_repairs``);
- the colony searches a box around the pair (``crop_margin``, 50 mm); when the box does not
  connect the pair its margin grows (``crop_growth``, x2 each time) until it does, never past
  ``max_search_voxels`` voxels (then :class:`SearchLimitError`, a :class:`PlanningError` naming
  the pair); the exact search runs on the whole grid when the grid is within that cap, else on
  the same growing boxes (then it is exact within the box only);
- the exact baseline forbids corner cutting by default (``corner_cutting``);
- the secondary optimisation stops after ``max_so_passes`` passes (a guard; it converges first).

Lengths: ``LocalPath.inner_length`` is measured between the virtual joints, like the paper's
Table 3 (the paper ignores the legs); ``LocalPath.length`` includes the legs.
"""

from __future__ import annotations

import json
import logging
import math
import time
import weakref
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from weldplan.errors import PlanningError
from weldplan.geometry.collision import CollisionModel
from weldplan.geometry.grid import ObstacleGrid
from weldplan.geometry.gridsearch import PaddedGrid, pad_free, shortest_grid_path
from weldplan.optim.discrete.aco_grid import AntColonyParams, ant_colony_grid
from weldplan.random import RNGLike, as_generator, seed_of

log = logging.getLogger(__name__)

__all__ = [
    "MAX_SEARCH_VOXELS",
    "METHODS",
    "LocalParams",
    "LocalPath",
    "SearchLimitError",
    "SecondaryResult",
    "plan_local_path",
    "plan_pair",
    "polyline_length",
    "secondary_optimization",
]

#: the local planners by name
METHODS = ("so-aco", "aco", "exact")

#: default cap on the voxels one pair's search box may span (:attr:`LocalParams.max_search_voxels`):
#: the colony holds about 250 bytes a voxel at N = M = 10 (pheromone, roulette weights and
#: heuristic per move, tabu lists), so 2 M voxels keep one pair near 0.5 GB; a box of 2 M voxels
#: is a cube of 126 voxels (630 mm at 5 mm)
MAX_SEARCH_VOXELS = 2_000_000


class SearchLimitError(PlanningError):
    """No search box within :attr:`LocalParams.max_search_voxels` connects the pair.

    Attributes
    ----------
    voxels
        Voxels of the largest box tried.
    cap
        The cap.
    """

    def __init__(self, message: str, *, voxels: int, cap: int) -> None:
        super().__init__(message)
        self.voxels = int(voxels)
        self.cap = int(cap)


#: two route lengths closer than this (mm) are "the same" in step 8 of section 4.3
SO_LENGTH_TOL = 1e-6


def polyline_length(points: ArrayLike) -> float:
    """Length (mm) of the polyline ``points (n, 3)``."""
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(P) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())


def _split(points: NDArray[np.float64], step: float) -> NDArray[np.float64]:
    """Split every segment longer than ``step`` into equal pieces no longer than ``step``."""
    out = [points[:1]]
    for a, b in zip(points[:-1], points[1:], strict=True):
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / step - 1e-9))
        t = np.arange(1, n, dtype=np.float64)[:, None] / n
        out.append(a + t * (b - a))
        out.append(b[None])  # the vertex itself, bit for bit
    return np.concatenate(out)


@dataclass(frozen=True, eq=False)
class SecondaryResult:
    """Outcome of :func:`secondary_optimization`.

    Attributes
    ----------
    points
        ``(n, 3) float`` the optimised route (mm), same first and last point as the input.
    passes
        Passes of steps 1-8 run.
    checks
        Segment checks made.
    converged
        False when ``max_passes`` or the deadline stopped it before the length settled.
    bad_segment
        With ``check_adjacent``: index ``k`` of the first segment ``k -> k + 1`` of the input
        that had to be kept and failed the check (``points`` is then the input); ``-1`` when a
        kept segment failed in a later pass (it cannot happen in exact arithmetic: later
        segments are pieces of checked ones); ``None`` when every kept segment is free.
    """

    points: NDArray[np.float64]
    passes: int
    checks: int
    converged: bool
    bad_segment: int | None = None


def secondary_optimization(
    points: ArrayLike,
    segment_free: Callable[[NDArray[np.float64], NDArray[np.float64]], bool],
    *,
    step: float = 5.0,
    max_passes: int = 100,
    deadline: float | None = None,
    check_adjacent: bool = False,
) -> SecondaryResult:
    """The secondary optimisation (SO) of Wang et al. 2017, section 4.3, steps 1-10.

    From the last kept point ``p``, try the points of the route from the last one backwards and
    keep the first ``q`` that ``p`` sees in a straight line (steps 3-6; the point right after
    ``p`` is kept without a check, as in step 4: consecutive points of the input must be
    connected by free segments). Repeat from ``q`` until the end (step 7). If the new route is
    shorter (step 8), split its segments longer than ``step`` into points, reverse it and start
    again (step 9); otherwise it is the result (step 10).

    Parameters
    ----------
    points
        ``(n, 3) float`` route (mm) whose consecutive points are joined by free segments.
    segment_free
        ``segment_free(a, b) -> bool`` for points ``(3,)``: the straight-line check (the FCL
        capsule at the clearance in weldplan).
    step
        The split length of step 9 (5 mm, the grid step, in the paper).
    max_passes
        Stop after this many passes (a guard; the length decreases at every pass).
    deadline
        ``time.perf_counter()`` value after which it stops and returns the route so far (still
        collision-free: every pass only replaces points by checked shortcuts).
    check_adjacent
        Also check the segment to the next point when step 4 keeps it without a check, and stop
        with ``bad_segment`` when it fails (weldplan's grid routes are only candidates: a
        lattice move can graze a sharp edge; the paper assumes they are free).

    Returns
    -------
    SecondaryResult
        The route, oriented like the input, never longer than the input.
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    first = P[0].copy()
    rout = P
    checks = 0
    passes = 0
    converged = False
    result = P
    while passes < max_passes:
        if passes and deadline is not None and time.perf_counter() > deadline:
            break  # the first pass always runs: it is the one that checks the input's moves
        passes += 1
        n = len(rout)
        keep = [0]
        i = 0
        while i < n - 1:
            q = n - 1
            while q > i + 1:
                checks += 1
                if segment_free(rout[i], rout[q]):
                    break
                q -= 1
            if check_adjacent and q == i + 1:
                checks += 1
                if not segment_free(rout[i], rout[q]):
                    bad = i if passes == 1 else -1
                    return SecondaryResult(P, passes, checks, False, bad)
            keep.append(q)
            i = q
        routi = rout[keep]
        result = routi
        if polyline_length(rout) - polyline_length(routi) <= SO_LENGTH_TOL:
            converged = True
            break
        rout = _split(routi, step)[::-1]
    if not np.array_equal(result[0], first):
        result = result[::-1]
    return SecondaryResult(np.ascontiguousarray(result), passes, checks, converged)


@dataclass(frozen=True)
class LocalParams:
    """Settings of the local planners.

    Attributes
    ----------
    colony
        Ant colony parameters (Table 2 of Wang et al. 2017 by default).
    so_step
        Split length of the secondary optimisation (mm); ``None``: the grid pitch (5 mm).
    max_so_passes
        Guard on the passes of the secondary optimisation.
    max_repairs
        Searches re-run after forbidding lattice moves that FCL rejected.
    connectivity
        Lattice of the exact baseline (26; 6 gives the ants' lattice).
    corner_cutting
        Let the exact baseline's diagonal moves pass between obstacle voxels (True: plain
        26-connectivity). False (default) allows a diagonal move only when every voxel of the
        box it spans is free: such moves rarely graze the part, so the FCL repair (a second
        search) is rarely needed; on the stand-in panel cell it removed the repair and halved
        the FCL checks for the same time.
    crop_margin
        The colony searches the box spanned by the two virtual joints grown by this margin (mm),
        not the whole grid. ``None``: the whole grid while it is within ``max_search_voxels``,
        else boxes grown from the pair's own box.
        The paper does not say how far its grid reached; a cell's region of interest covers
        every joint (1 M voxels on the demo cell, 74 M on car2's 1000-joint set), and the
        colony's arrays, its per-pair set-up and its ants' wanderings all grow with it. The exact
        search is not cropped while the grid is within ``max_search_voxels`` (A* touches only
        what it expands, but its move table spans the grid).
    crop_growth
        When a box does not connect the pair (6-connected free voxels inside it), its margin is
        multiplied by this factor and the search box built again, until it connects the pair,
        covers the grid, or would exceed ``max_search_voxels`` (then the largest margin within
        the cap is tried last).
    max_search_voxels
        Most voxels one pair's search box may span (:data:`MAX_SEARCH_VOXELS`, about 0.5 GB for
        the colony); beyond it :func:`plan_local_path` raises :class:`SearchLimitError` naming
        the pair. ``None``: no cap.
    """

    colony: AntColonyParams = field(default_factory=AntColonyParams)
    so_step: float | None = None
    max_so_passes: int = 100
    max_repairs: int = 3
    connectivity: int = 26
    corner_cutting: bool = False
    crop_margin: float | None = 50.0
    crop_growth: float = 2.0
    max_search_voxels: int | None = MAX_SEARCH_VOXELS

    def __post_init__(self) -> None:
        if not self.crop_growth > 1.0:
            raise ValueError(f"crop_growth must be > 1, got {self.crop_growth}")
        if self.max_search_voxels is not None and self.max_search_voxels < 1:
            raise ValueError(f"max_search_voxels must be positive, got {self.max_search_voxels}")
        if self.crop_margin is not None and not self.crop_margin >= 0:
            raise ValueError(f"crop_margin must be >= 0 mm, got {self.crop_margin}")

    @classmethod
    def coerce(
        cls, params: LocalParams | AntColonyParams | Mapping[str, Any] | None
    ) -> LocalParams:
        """Accept ``None``, a :class:`LocalParams`, an :class:`AntColonyParams`, or a flat
        mapping whose keys are fields of either (``{"n_iterations": 10, "n_ants": 10}``)."""
        if params is None:
            return cls()
        if isinstance(params, LocalParams):
            return params
        if isinstance(params, AntColonyParams):
            return cls(colony=params)
        colony_keys = {f.name for f in fields(AntColonyParams)}
        own_keys = {f.name for f in fields(cls)} - {"colony"}
        unknown = set(params) - colony_keys - own_keys
        if unknown:
            raise ValueError(
                f"unknown local-planner parameter(s) {sorted(unknown)}; "
                f"known: {sorted(colony_keys | own_keys)}"
            )
        colony = params.get("colony")
        if isinstance(colony, Mapping):
            colony = AntColonyParams(**colony)
        if colony is None:
            colony = AntColonyParams(**{k: v for k, v in params.items() if k in colony_keys})
        return cls(colony=colony, **{k: v for k, v in params.items() if k in own_keys})

    def to_dict(self) -> dict:
        return asdict(self)


def _f(x: float) -> float | None:
    return None if not math.isfinite(x) else float(x)


def _uf(x: float | None) -> float:
    return math.inf if x is None else float(x)


@dataclass(frozen=True, eq=False)
class LocalPath:
    """A joint-to-joint path.

    Attributes
    ----------
    points
        ``(n, 3) float`` world mm: real joint ``i``, its virtual joint, the route, the virtual
        joint of ``j``, real joint ``j`` (a leg is dropped when a joint is its own virtual joint).
        ``(0, 3)`` when planning failed.
    length
        Length of the whole polyline (mm), legs included; ``inf`` on failure.
    inner_length
        Length between the two virtual joints (mm), the quantity the paper reports.
    method
        ``"so-aco"``, ``"aco"`` or ``"exact"``.
    success
        Whether a collision-free path was found.
    reason
        Why not (empty on success), or a note (``"straight segment free"`` on the fast path).
    fast_path
        The straight segment between the virtual joints was free; no search ran.
    raw_length
        Length of the grid route before the secondary optimisation (mm).
    iterations, ants, evaluations
        Colony iterations and ant walks completed; ``evaluations`` counts ant walks for the
        colony and node expansions for the exact search.
    seconds
        Wall time of the whole planning call.
    cpu_seconds
        Processor time of the call (``time.process_time``): close to the wall time on an idle
        core, and far less sensitive than it to other processes sharing the machine.
    seed
        The integer seed when ``rng`` was one.
    so_passes, collision_checks, repairs
        Secondary-optimisation passes, FCL segment checks, searches re-run after FCL rejected a
        lattice move.
    search_voxels
        Voxels of the box the search ran on (the whole grid when uncropped; 0 when no search
        ran): what bounds the search's memory.
    search_boxes
        Boxes built before one connected the pair (0: the whole grid without cropping).
    history
        Best raw route length after each colony iteration (mm), for convergence plots.
    """

    points: NDArray[np.float64]
    length: float
    inner_length: float
    method: str
    success: bool
    reason: str = ""
    fast_path: bool = False
    raw_length: float = math.inf
    iterations: int = 0
    ants: int = 0
    evaluations: int = 0
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    seed: int | None = None
    so_passes: int = 0
    collision_checks: int = 0
    repairs: int = 0
    search_voxels: int = 0
    search_boxes: int = 0
    history: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        pts = np.array(self.points, dtype=np.float64).reshape(-1, 3)
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "history", tuple(float(h) for h in self.history))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (``inf`` as ``None``)."""
        d: dict[str, Any] = {f.name: getattr(self, f.name) for f in fields(self)}
        d["points"] = self.points.tolist()
        for k in ("length", "inner_length", "raw_length"):
            d[k] = _f(d[k])
        d["history"] = [_f(h) for h in self.history]
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> LocalPath:
        kw = dict(d)
        for k in ("length", "inner_length", "raw_length"):
            kw[k] = _uf(kw.get(k))
        kw["history"] = tuple(_uf(h) for h in kw.get("history", ()))
        kw["points"] = np.asarray(kw.get("points", []), dtype=np.float64).reshape(-1, 3)
        return cls(**kw)

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_json(cls, text: str) -> LocalPath:
        return cls.from_dict(json.loads(text))


# ---------------------------------------------------------------------------------------------
# per-grid caches (padded array, connected components): built once, shared by every pair
_PADDED: weakref.WeakKeyDictionary[ObstacleGrid, PaddedGrid] = weakref.WeakKeyDictionary()
_LABELS: weakref.WeakKeyDictionary[ObstacleGrid, dict[int, NDArray[np.int32]]] = (
    weakref.WeakKeyDictionary()
)


def _padded(grid: ObstacleGrid) -> PaddedGrid:
    pg = _PADDED.get(grid)
    if pg is None:
        pg = _PADDED[grid] = pad_free(grid.free)
    return pg


def _box(
    shape: NDArray[np.int64], s: NDArray[np.int64], g: NDArray[np.int64], m: int
) -> tuple[NDArray[np.int64], NDArray[np.int64], int]:
    lo = np.maximum(np.minimum(s, g) - m, 0)
    hi = np.minimum(np.maximum(s, g) + m + 1, shape)
    return lo, hi, int(np.prod(hi - lo))


def _search_grid(
    grid: ObstacleGrid,
    s: NDArray[np.int64],
    g: NDArray[np.int64],
    method: str,
    prm: LocalParams,
    label_conn: int,
) -> tuple[PaddedGrid, NDArray[np.int64], int, int]:
    """The padded array a search runs on, the grid index of its voxel (0, 0, 0), its voxels and
    the boxes built to find it (:class:`LocalParams` ``crop_margin``, ``crop_growth``,
    ``max_search_voxels``).

    Raises
    ------
    SearchLimitError
        No box within the cap connects the pair.
    """
    zero = np.zeros(3, dtype=np.int64)
    shape = np.asarray(grid.shape, dtype=np.int64)
    n_grid = int(np.prod(shape))
    cap = prm.max_search_voxels
    whole_ok = cap is None or n_grid <= cap
    where = f"virtual joints {s.tolist()} -> {g.tolist()}"
    if whole_ok and (method == "exact" or prm.crop_margin is None):
        return _padded(grid), zero, n_grid, 0
    structure = ndimage.generate_binary_structure(3, 1 if label_conn == 6 else 3)
    margin = (prm.crop_margin or 0.0) / grid.pitch
    m = int(math.ceil(margin))
    boxes = 0
    last_fit = -1  # the largest margin (voxels) tried within the cap
    while True:
        lo, hi, vox = _box(shape, s, g, m)
        if cap is not None and vox > cap:
            # the largest margin within the cap, if not tried yet (bisection on the margin)
            a, b = last_fit, m
            while b - a > 1:
                mid = (a + b) // 2
                if _box(shape, s, g, mid)[2] <= cap:
                    a = mid
                else:
                    b = mid
            if a <= last_fit:
                raise SearchLimitError(
                    f"no search box within {cap:,} voxels connects {where} (the next box spans "
                    f"{vox:,} voxels, {boxes} tried; the pair may lie on both sides of a panel): "
                    "raise max_search_voxels to search farther",
                    voxels=vox,
                    cap=cap,
                )
            m = a
            lo, hi, vox = _box(shape, s, g, m)
        boxes += 1
        if vox == n_grid:  # the whole grid (connectivity was checked on it)
            return _padded(grid), zero, n_grid, boxes
        sub = grid.free[lo[0] : hi[0], lo[1] : hi[1], lo[2] : hi[2]]
        labels, _ = ndimage.label(sub, structure=structure)
        if labels[tuple(s - lo)] == labels[tuple(g - lo)]:
            return pad_free(sub), lo, vox, boxes
        del labels
        log.debug("box %d (%d voxels) does not connect %s; growing it", boxes, vox, where)
        last_fit = m
        margin = max(margin, 1.0) * prm.crop_growth
        m = max(m + 1, int(math.ceil(margin)))


def _connected(grid: ObstacleGrid, a: NDArray[np.int64], b: NDArray[np.int64], conn: int) -> bool:
    by_conn = _LABELS.setdefault(grid, {})
    labels = by_conn.get(conn)
    if labels is None:
        structure = ndimage.generate_binary_structure(3, 1 if conn == 6 else 3)
        labels, _ = ndimage.label(grid.free, structure=structure)
        by_conn[conn] = labels
    return bool(labels[tuple(a)] == labels[tuple(b)] != 0)


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


def _bad_moves(P: NDArray[np.float64], seg_free: Callable[..., bool]) -> list[int]:
    """Indices ``k`` of the segments ``P[k] -> P[k + 1]`` that fail ``seg_free``."""
    return [k for k in range(len(P) - 1) if not seg_free(P[k], P[k + 1])]


def plan_local_path(
    grid: ObstacleGrid,
    collision: CollisionModel,
    start_xyz: ArrayLike,
    goal_xyz: ArrayLike,
    start_idx: ArrayLike,
    goal_idx: ArrayLike,
    *,
    method: str = "so-aco",
    params: LocalParams | AntColonyParams | Mapping[str, Any] | None = None,
    rng: RNGLike = None,
    time_budget: float | None = None,
    callback: Callable[[int, float], None] | None = None,
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
    method
        ``"so-aco"`` (default), ``"aco"`` or ``"exact"``.
    params
        :class:`LocalParams`, :class:`AntColonyParams` or a flat mapping of their fields.
    rng
        Seed or generator (the colony's only source of randomness).
    time_budget
        Seconds; the colony stops between steps, A* between expansions, the secondary
        optimisation between passes. Without a route when time runs out: ``success=False``.
    callback
        ``callback(iteration, best_length)`` after each colony iteration.

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
        For an unknown method or parameter.
    """
    t0 = time.perf_counter()
    c0 = time.process_time()
    if method not in METHODS:
        raise ValueError(f"unknown local-path method {method!r}; choose one of {METHODS}")
    prm = LocalParams.coerce(params)
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
    radius = grid.clearance
    vs = grid.index_to_world(s)
    vg = grid.index_to_world(g)
    checks = 0

    def seg_free(a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
        # one fcl capsule query (~16 us); the sphere-traced batch check pays off only for many
        # segments at once, and the secondary optimisation asks one segment at a time
        nonlocal checks
        checks += 1
        return bool(collision.segments_free(a[None], b[None], radius, method="fcl")[0])

    def done(**kw: Any) -> LocalPath:
        kw.setdefault("points", np.zeros((0, 3)))
        pts = kw["points"]
        success = kw.setdefault("success", len(pts) > 0)
        kw.setdefault("length", polyline_length(pts) if success else math.inf)
        return LocalPath(
            method=method,
            seed=seed,
            collision_checks=checks,
            seconds=time.perf_counter() - t0,
            cpu_seconds=time.process_time() - c0,
            **kw,
        )

    # fast path: the straight segment between the virtual joints is free
    if np.array_equal(s, g) or seg_free(vs, vg):
        inner = vs[None] if np.array_equal(s, g) else np.stack([vs, vg])
        d = polyline_length(inner)
        return done(
            points=_assemble(start_xyz, inner, goal_xyz),
            inner_length=d,
            raw_length=d,
            fast_path=True,
            reason="straight segment free",
        )

    conn = 6 if method != "exact" else prm.connectivity
    # diagonal moves without corner cutting reach exactly the 6-connected region
    label_conn = 6 if method != "exact" or not prm.corner_cutting else conn
    if not _connected(grid, s, g, label_conn):
        return done(
            inner_length=math.inf,
            reason=f"goal not reachable from start: different {label_conn}-connected free "
            "regions (enclosed, or cut off by the region of interest)",
        )

    pg, origin, search_voxels, search_boxes = _search_grid(grid, s, g, method, prm, label_conn)
    stats_box = {"search_voxels": search_voxels, "search_boxes": search_boxes}
    blocked: set[tuple[int, int]] = set()
    stats: dict[str, Any] = {"iterations": 0, "ants": 0, "evaluations": 0, "history": ()}
    stats.update(stats_box)
    path_idx = None
    raw_len = math.inf
    repairs = 0
    for _ in range(prm.max_repairs + 1):
        if method == "exact":
            r = shortest_grid_path(
                pg, s - origin, g - origin, connectivity=conn, pitch=grid.pitch,
                blocked_edges=blocked, deadline=deadline, corner_cutting=prm.corner_cutting,
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
        if not r.success:
            return done(inner_length=math.inf, reason=r.reason, repairs=repairs, **stats)
        path = r.path + origin
        P = grid.index_to_world(path)
        if method == "aco":
            bad = _bad_moves(P, seg_free)
        else:
            so = secondary_optimization(
                P, seg_free, step=prm.so_step or grid.pitch, max_passes=prm.max_so_passes,
                deadline=deadline, check_adjacent=True,
            )  # fmt: skip
            bad = [] if so.bad_segment is None else [so.bad_segment]
            if bad == [-1]:  # a piece of a checked segment failed: check every move
                bad = _bad_moves(P, seg_free) or [-1]
        if not bad:
            path_idx, raw_len = path, r.length
            break
        if bad == [-1]:
            return done(inner_length=math.inf, repairs=repairs, reason=_FCL_EDGE, **stats)
        flat = pg.flat(r.path)
        blocked.update((int(flat[k]), int(flat[k + 1])) for k in bad)
        repairs += 1
        log.debug("%d lattice move(s) graze the part at the clearance; searching again", len(bad))
    if path_idx is None:
        return done(
            inner_length=math.inf,
            repairs=repairs,
            reason=f"grid routes kept grazing the part after {prm.max_repairs} repairs",
            **stats,
        )
    if method == "aco":
        inner, so_passes = grid.index_to_world(path_idx), 0
    else:
        inner, so_passes = so.points, so.passes
    return done(
        points=_assemble(start_xyz, inner, goal_xyz),
        inner_length=polyline_length(inner),
        raw_length=raw_len,
        so_passes=so_passes,
        repairs=repairs,
        **stats,
    )


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
        return plan_local_path(
            cell.grid,
            cell.collision,
            xyz[i],
            xyz[j],
            vidx[i],
            vidx[j],
            method=method,
            params=params,
            rng=rng,
            time_budget=time_budget,
            callback=callback,
        )
    except SearchLimitError as exc:
        ids = getattr(getattr(cell, "joints", None), "ids", None)
        name = f"{ids[i]} -> {ids[j]}" if ids is not None else f"{i} -> {j}"
        raise SearchLimitError(f"joints {name}: {exc}", voxels=exc.voxels, cap=exc.cap) from exc
