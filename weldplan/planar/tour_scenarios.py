"""Multi-goal traversal tasks (paper 002, section 3): a planar map, the start (depot) and the
goals, read from the shipped scenario files, built on a Polyanya navigation mesh, or taken from
rtb-data's house floorplan.

:mod:`weldplan.planar.tour_order` turns a task into stop-to-stop distances and orders the stops;
:mod:`weldplan.planar.tour_planner` plans the tour; :mod:`weldplan.planar.multigoal` re-exports
all three.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError
from weldplan.planar.scenarios import (
    SCENARIO_DIR,
    Scenario,
    available_scenarios,
    scenario_from_dict,
    scenario_path,
)

#: folder of the shipped multi-goal scenarios
TOUR_DIR = SCENARIO_DIR / "tours"


# ------------------------------------------------------------------------------ scenarios
@dataclass(frozen=True, eq=False)
class TourScenario:
    """A multi-goal traversal task: a planar map (``scenario``, whose ``start`` is the depot),
    ``goals (t, 2)`` to visit, and the mesh edge length ``max_edge`` (M) it was made for.

    A task on a Polyanya navigation mesh (:func:`navmesh_tour`) has ``space`` (a
    :class:`~weldplan.planar.exact.MeshFreeSpace`) instead of ``scenario``.
    """

    scenario: Scenario | None
    goals: NDArray[np.float64]
    max_edge: float
    space: Any = None
    start_point: NDArray[np.float64] | None = None
    label: str = ""

    @property
    def name(self) -> str:
        return self.scenario.name if self.scenario is not None else self.label

    @property
    def start(self) -> NDArray[np.float64]:
        if self.scenario is not None:
            return np.asarray(self.scenario.start, dtype=np.float64)
        return np.asarray(self.start_point, dtype=np.float64)

    @property
    def world(self) -> Any:
        """What the smoothing loop checks paths against: the scenario's obstacles with the map
        frame, the navigation mesh's free space, or for a map that is only an occupancy grid a
        :class:`SampledGridWorld` (on the house floorplan's 3,838 touching grid rectangles
        the exact check costs 0.4 s a call, about ten times the sampled one, and the loop may
        call it dozens of times)."""
        if self.scenario is None:
            return self.space
        sc = self.scenario
        if sc.grid is not None and not len(sc.obstacles.circles) and not sc.obstacles.polygons:
            return SampledGridWorld(sc.grid, sc.bounds)
        return sc.world

    @property
    def exact_world(self) -> Any:
        """What the returned path is finally judged by: the exact segment check (the
        scenario's obstacles with the map frame, or the navigation mesh), also on grid maps."""
        return self.space if self.scenario is None else self.scenario.world

    @property
    def stops(self) -> NDArray[np.float64]:
        """``(t + 1, 2)``: the start, then the goals."""
        return np.concatenate([self.start[None], self.goals])


def navmesh_tour(
    space: Any, start: ArrayLike, goals: ArrayLike, max_edge: float = np.inf, label: str = "navmesh"
) -> TourScenario:
    """A multi-goal task on a Polyanya navigation mesh (``space``: a
    :class:`~weldplan.planar.exact.MeshFreeSpace`), refined to edges of ``max_edge`` (``inf``:
    Triangle's quality mesh of the navmesh boundary alone).

    Raises
    ------
    InputError
        When the start or a goal is outside the mesh.
    """
    S = np.asarray(start, dtype=np.float64).reshape(2)
    G = np.asarray(goals, dtype=np.float64).reshape(-1, 2)
    inside = space.contains_free(np.concatenate([S[None], G]))
    if not inside.all():
        k = int(np.argmin(inside))
        raise InputError(
            f"point {np.concatenate([S[None], G])[k].tolist()} is outside the navigation mesh",
            field="start" if k == 0 else f"goals[{k - 1}]",
        )
    return TourScenario(
        scenario=None, goals=G, max_edge=float(max_edge), space=space, start_point=S, label=label
    )


class SampledGridWorld:
    """Segment checks on an occupancy grid by sampling: a segment is free when every point at
    steps of at most ``cell / samples_per_cell`` along it (ends included) lies in a free cell
    inside the bounds, cell boundaries counting as free. A stated approximation: a segment may
    clip the corner of an occupied cell by less than ``cell / samples_per_cell``."""

    def __init__(self, grid: Any, bounds: ArrayLike, samples_per_cell: int = 16) -> None:
        self.grid = grid
        self.bounds = np.asarray(bounds, dtype=np.float64)
        self.step = grid.cell / float(samples_per_cell)
        self.scale = float(np.hypot(*(self.bounds[2:] - self.bounds[:2])))

    def points_free(self, P: ArrayLike) -> NDArray[np.bool_]:
        P = np.asarray(P, dtype=np.float64)
        g = self.grid
        nx, ny = g.shape
        eps = 1e-9 * g.cell
        b = self.bounds
        ok = (
            (P[..., 0] >= b[0] - eps)
            & (P[..., 0] <= b[2] + eps)
            & (P[..., 1] >= b[1] - eps)
            & (P[..., 1] <= b[3] + eps)
        )
        # a point on a cell boundary is free when any cell it touches is free
        free = np.zeros(P.shape[:-1], dtype=bool)
        for dx in (-eps, eps):
            for dy in (-eps, eps):
                ij = g.cell_of(P + np.array([dx, dy]))
                inside = (
                    (ij[..., 0] >= 0) & (ij[..., 0] < nx) & (ij[..., 1] >= 0) & (ij[..., 1] < ny)
                )
                occ = np.ones(P.shape[:-1], dtype=bool)
                occ[inside] = g.occupied[ij[inside][:, 0], ij[inside][:, 1]]
                free |= ~occ
        return ok & free

    def segments_free(self, A: ArrayLike, B: ArrayLike) -> NDArray[np.bool_]:
        A = np.asarray(A, dtype=np.float64).reshape(-1, 2)
        B = np.asarray(B, dtype=np.float64).reshape(-1, 2)
        n = np.maximum(1, np.ceil(np.linalg.norm(B - A, axis=1) / self.step)).astype(np.int64)
        seg = np.repeat(np.arange(len(A)), n + 1)
        t = np.concatenate([np.linspace(0.0, 1.0, k + 1) for k in n.tolist()]) if len(A) else []
        t = np.asarray(t)[:, None]
        P = A[seg] + t * (B[seg] - A[seg])
        ok = self.points_free(P)
        out = np.ones(len(A), dtype=bool)
        np.logical_and.at(out, seg, ok)
        return out

    def contains_free(self, P: ArrayLike) -> NDArray[np.bool_]:
        return self.points_free(P)


def tour_path(name_or_path: str | Path) -> Path:
    """The file of a shipped multi-goal scenario by name (``tour-1``) or the path itself."""
    return scenario_path(name_or_path, TOUR_DIR)


def available_tours() -> list[str]:
    """Names of the multi-goal scenarios shipped under ``assets/scenarios/tours``."""
    return available_scenarios(TOUR_DIR)


def load_tour(name_or_path: str | Path) -> TourScenario:
    """Read a multi-goal scenario: a planar scenario file (see
    :mod:`weldplan.planar.scenarios`) with ``"goals": [[x, y], ...]`` instead of ``"goal"`` and
    ``"max_edge": M``."""
    path = tour_path(name_or_path)
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg}", path=path, line=exc.lineno) from None
    return tour_from_dict(data, path=path)


def tour_from_dict(data: Any, *, path: Any = None) -> TourScenario:
    if not isinstance(data, dict):
        raise InputError("a scenario must be a JSON object", path=path)
    goals_raw = data.get("goals")
    if not isinstance(goals_raw, list) or not goals_raw:
        raise InputError(
            "a multi-goal scenario needs 'goals', a list of points", path=path, field="goals"
        )
    d = dict(data)
    d.setdefault("goal", goals_raw[0])
    sc = scenario_from_dict(d, path=path)
    goals = []
    b = sc.bounds
    for k, g in enumerate(goals_raw):
        sub = scenario_from_dict({**d, "goal": g}, path=path) if k else sc
        p = np.asarray(sub.goal, dtype=np.float64)
        if not (b[0] <= p[0] <= b[2] and b[1] <= p[1] <= b[3]):  # pragma: no cover - checked above
            raise InputError("goal outside the bounds", path=path, field=f"goals[{k}]")
        goals.append(p)
    G = np.array(goals)
    if len(np.unique(np.round(np.concatenate([sc.start[None], G]), 9), axis=0)) != len(G) + 1:
        raise InputError(
            "goals must be distinct from each other and from the start", path=path, field="goals"
        )
    M = data.get("max_edge", 0.02 * float(b[2] - b[0]))
    if not isinstance(M, (int, float)) or isinstance(M, bool) or M <= 0:
        raise InputError("max_edge must be a positive number", path=path, field="max_edge")
    G.setflags(write=False)
    return TourScenario(scenario=sc, goals=G, max_edge=float(M))


# ------------------------------------------------------------------------------ real maps
#: the named places of rtb-data's house floorplan, in the order they are read
HOUSE_START = "kitchen"


def house_tour(max_edge: float = 4.0, start: str = HOUSE_START) -> TourScenario:
    """The floorplan ``house.mat`` of the PyPI package ``rtb-data`` (Corke's Robotics Toolbox
    data, MIT) as a multi-goal task: the occupancy grid (596 x 397 cells of 1 unit, value 1 =
    obstacle, indexed ``[y, x]``) becomes grid obstacles, ``start`` the depot and the other
    named places the goals (place coordinates are cell centres ``(x, y)``).

    Raises
    ------
    ImportError
        When ``rtb-data`` is not installed (``pip install weldplan[test]``).
    """
    try:
        import rtbdata
    except ImportError as exc:
        raise ImportError(
            "the house floorplan needs the 'rtb-data' package (pip install 'weldplan[test]')"
        ) from exc
    from scipy.io import loadmat

    path = Path(rtbdata.__file__).parent / "data" / "house.mat"
    d = loadmat(path, squeeze_me=True, struct_as_record=False)
    occ = np.asarray(d["floorplan"]) != 0  # (ny, nx), row 0 at y = 0
    places = {n: np.asarray(getattr(d["places"], n), dtype=np.float64)
              for n in d["places"]._fieldnames}  # fmt: skip
    if start not in places:
        raise InputError(f"unknown place {start!r}; one of {sorted(places)}", path=path)
    ny, nx = occ.shape
    rows = ["".join("#" if v else "." for v in r) for r in occ[::-1]]
    goals = [p.tolist() for n, p in places.items() if n != start]
    data = {
        "name": "house",
        "description": "rtb-data house.mat floorplan; goals: "
        + ", ".join(n for n in places if n != start),
        "bounds": [-0.5, -0.5, nx - 0.5, ny - 0.5],
        "start": places[start].tolist(),
        "goals": goals,
        "max_edge": float(max_edge),
        "obstacles": [{"type": "grid", "origin": [-0.5, -0.5], "cell": 1.0, "rows": rows}],
    }
    return tour_from_dict(data, path=path)
