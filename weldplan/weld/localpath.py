"""The local planners' settings, result and errors (split out of :mod:`weldplan.weld.local`)."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import ConfigError, PlanningError
from weldplan.optim.discrete.aco_grid import AntColonyParams
from weldplan.weld.homotopy import CLASS_RADIUS, CLASS_SLACK

__all__ = [
    "MAX_SEARCH_VOXELS",
    "METHODS",
    "REFINE_BUDGET",
    "LocalParams",
    "LocalPath",
    "SearchLimitError",
]

#: the local planners by name
METHODS = ("so-aco", "aco", "exact")

#: default cap on the voxels one pair's search box may span (:attr:`LocalParams.max_search_voxels`):
#: the colony holds about 250 bytes a voxel at N = M = 10 (pheromone, roulette weights and
#: heuristic per move, tabu lists), so 2 M voxels keep one pair near 0.5 GB; a box of 2 M voxels
#: is a cube of 126 voxels (630 mm at 5 mm)
MAX_SEARCH_VOXELS = 2_000_000

#: default CPU-time cap (s) on the continuous refinement of one pair
#: (:attr:`LocalParams.refine_budget`), a safety net: the work is bounded by the vertex
#: optimisation's rounds (:data:`weldplan.weld.taut.MAX_ROUNDS`) and the sweeps' count. The
#: bench's 32 blocked pairs take 0.01-0.25 s of CPU each for the whole refinement; a cap near
#: that (0.5 s before) cut outliers at a point that depends on the machine's speed, so the
#: same seed could give another path elsewhere (../shared/DESIGN.md, reproducibility)
REFINE_BUDGET = 5.0


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
        Searches re-run after forbidding lattice moves that FCL rejected; ``None`` (default):
        until a route passes or none is left (each repair forbids at least one more move, so
        it ends; ``time_budget`` bounds it in time). It was 3, and on routes along long sheet
        edges that gave up where a path existed.
    refine
        Run the continuous refinement (:mod:`weldplan.weld.refine`) on the path between the
        virtual joints. Off here (the paper's planners as printed); the planning pipeline turns
        it on (:data:`weldplan.weld.pipeline.DEFAULT_ACO`).
    refine_taut
        The refinement's second stage is the joint vertex optimisation
        (:mod:`weldplan.weld.taut`, the default); False: the one-vertex sweeps
        (:func:`weldplan.weld.refine.tighten_path`), as before.
    refine_budget
        CPU seconds (of the planning thread, :func:`time.thread_time`) the refinement of one
        pair may take (its vertex optimisation stops between rounds; what it has is checked and
        kept); ``None``: no cap. Typical pairs take 0.01-0.1 s; the cap bounds the few that take
        longer on large stations. CPU, not wall time, so that a loaded machine (or the other
        workers of a parallel run) does not change the path.
    second_class
        With ``refine`` and the exact planner: the second-class stage
        (:mod:`weldplan.weld.homotopy`): a second A* route outside the first route's corridor,
        refined under the same ``refine_budget`` when its grid path is within ``class_slack`` of
        the first's, the shorter refined path kept. On by default (it does nothing unless
        ``refine`` is on); False: one route, as before. On the 151 blocked pairs of
        ``weldplan bench local --peers`` it brought the max length from 1.018 to 1.006 x OMPL
        BIT* 10 s; it costs about a quarter more CPU in a whole plan of car2's 200-joint
        station, for no length there (docs/bench-local-peers.md).
    class_radius
        Radius of the first route's corridor that the second route may not enter (mm,
        :data:`weldplan.weld.homotopy.CLASS_RADIUS`).
    class_slack
        The second candidate is refined when its length after the secondary optimisation is at
        most ``1 + class_slack`` times the first's (:data:`weldplan.weld.homotopy.CLASS_SLACK`).
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
    max_repairs: int | None = None
    refine: bool = False
    refine_taut: bool = True
    refine_budget: float | None = REFINE_BUDGET
    second_class: bool = True
    class_radius: float = CLASS_RADIUS
    class_slack: float = CLASS_SLACK
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
        if self.max_repairs is not None and self.max_repairs < 0:
            raise ValueError(f"max_repairs must be >= 0 or None, got {self.max_repairs}")
        if self.refine_budget is not None and not self.refine_budget >= 0:
            raise ValueError(f"refine_budget must be >= 0 s or None, got {self.refine_budget}")
        if not (math.isfinite(self.class_radius) and self.class_radius > 0):
            raise ValueError(
                f"class_radius must be a positive length (mm), got {self.class_radius}"
            )
        if not (math.isfinite(self.class_slack) and self.class_slack >= 0):
            raise ValueError(f"class_slack must be a finite number >= 0, got {self.class_slack}")
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


@dataclass(frozen=True)
class LocalSearchSettings:
    """How :func:`~weldplan.weld.local.plan_local_path` searches one pair: one frozen object,
    validated once (../shared/DESIGN.md: a stage takes its inputs and one settings object).

    Attributes
    ----------
    method
        ``"so-aco"`` (default), ``"aco"`` or ``"exact"`` (:mod:`weldplan.weld.local`).
    params
        The planners' settings: a :class:`LocalParams`, or anything
        :meth:`LocalParams.coerce` takes (an :class:`AntColonyParams`, a flat mapping of their
        fields, ``None``), turned into one when the settings are made.
    time_budget
        Seconds; the colony stops between steps, A* between expansions, the secondary
        optimisation between passes. Without a route when time runs out: ``success=False``.
        ``None``: no limit.
    """

    method: str = "so-aco"
    params: LocalParams = field(default_factory=LocalParams)
    time_budget: float | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ConfigError(
                f"unknown local-path method {self.method!r}; choose one of {METHODS}",
                field="method",
            )
        object.__setattr__(self, "params", LocalParams.coerce(self.params))
        b = self.time_budget
        if b is not None and not (isinstance(b, (int, float)) and not isinstance(b, bool)):
            raise ConfigError(
                f"time_budget must be seconds or None, got {b!r}", field="time_budget"
            )


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
    so_length
        Length between the virtual joints after the secondary optimisation, before the
        continuous refinement (mm; ``inf`` when planning failed).
    refined
        The continuous refinement ran and shortened the path (``inner_length < so_length``).
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
    classes
        Grid routes refined and compared: 2 when the second-class stage
        (:mod:`weldplan.weld.homotopy`) refined a candidate, else 1.
    second_class
        The path kept is the second-class candidate (it refined shorter than the first route).
    refine_clock_stops
        Refinements of this pair (first and second class) whose CPU-time cap
        (:attr:`LocalParams.refine_budget`) was spent: the path may then depend on the machine
        (:attr:`weldplan.weld.refine.RefinedPath.clock_stopped`); 0 when reproducible.
    """

    points: NDArray[np.float64]
    length: float
    inner_length: float
    method: str
    success: bool
    reason: str = ""
    fast_path: bool = False
    raw_length: float = math.inf
    so_length: float = math.inf
    refined: bool = False
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
    classes: int = 1
    second_class: bool = False
    refine_clock_stops: int = 0

    def __post_init__(self) -> None:
        pts = np.array(self.points, dtype=np.float64).reshape(-1, 3)
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "history", tuple(float(h) for h in self.history))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (``inf`` as ``None``)."""
        d: dict[str, Any] = {f.name: getattr(self, f.name) for f in fields(self)}
        d["points"] = self.points.tolist()
        for k in ("length", "inner_length", "raw_length", "so_length"):
            d[k] = _f(d[k])
        d["history"] = [_f(h) for h in self.history]
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> LocalPath:
        kw = dict(d)
        for k in ("length", "inner_length", "raw_length", "so_length"):
            kw[k] = _uf(kw.get(k))
        kw["history"] = tuple(_uf(h) for h in kw.get("history", ()))
        kw["points"] = np.asarray(kw.get("points", []), dtype=np.float64).reshape(-1, 3)
        return cls(**kw)

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_json(cls, text: str) -> LocalPath:
        return cls.from_dict(json.loads(text))
