"""Planar scenarios: the JSON files under ``assets/scenarios/``, loaded and validated.

A scenario file is one JSON object::

    {
      "name": "circles-1",
      "description": "...",
      "bounds": [xmin, ymin, xmax, ymax],
      "start": [x, y],
      "goal": [x, y],
      "obstacles": [
        {"type": "circle", "center": [x, y], "radius": r},
        {"type": "rectangle", "min": [x, y], "max": [x, y]},
        {"type": "polygon", "vertices": [[x, y], [x, y], [x, y], ...]},
        {"type": "grid", "origin": [x, y], "cell": 1.0, "rows": ["..#.", "...."]}
      ],
      "encoding": "spline" | "segments" | "grid",   (the encoding the scenario was made for)
      "nodes": 12                                    (free nodes of the segment encoding)
    }

A ``grid`` obstacle is an occupancy grid written as text, ``#`` occupied and ``.`` free, the
first row the top one (largest y), as a map is drawn. At most one grid per scenario; the
grid encoding (paper 001) plans on it.

Every problem is reported as an :class:`~weldplan.errors.InputError` naming the file and the
field (``obstacles[3].vertices``): unknown obstacle types, bad numbers, self-intersecting
polygons, a start or goal outside the bounds or inside an obstacle.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.geometry.obstacles2d import Obstacles2D, grid_to_rectangles, polygon_is_simple

log = logging.getLogger(__name__)

#: folder of the scenarios shipped with weldplan
SCENARIO_DIR = Path(__file__).resolve().parents[2] / "assets" / "scenarios"

OBSTACLE_TYPES = ("circle", "rectangle", "polygon", "grid")
ENCODINGS = ("spline", "segments", "grid")


@dataclass(frozen=True, eq=False)
class GridMap:
    """An occupancy grid: ``occupied (nx, ny) bool`` indexed ``[i, j]`` = cell at column i, row
    j; cell ``(i, j)`` covers ``[x0 + i c, x0 + (i+1) c] x [y0 + j c, y0 + (j+1) c]``."""

    occupied: NDArray[np.bool_]
    origin: tuple[float, float] = (0.0, 0.0)
    cell: float = 1.0

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.occupied.shape[0]), int(self.occupied.shape[1]))

    def cell_of(self, point: NDArray[np.float64]) -> NDArray[np.int64]:
        """Cell indices ``(..., 2)`` of points ``(..., 2)``."""
        p = (np.asarray(point, dtype=np.float64) - np.asarray(self.origin)) / self.cell
        return np.floor(p).astype(np.int64)

    def centre(self, ij: NDArray[np.int64]) -> NDArray[np.float64]:
        """World centres ``(..., 2)`` of cells ``(..., 2)``."""
        return np.asarray(self.origin) + (np.asarray(ij, dtype=np.float64) + 0.5) * self.cell


@dataclass(frozen=True, eq=False)
class Scenario:
    """A planar planning task.

    Attributes
    ----------
    name
        Short identifier (the file stem unless the file names one).
    bounds
        ``(4,)``: ``xmin, ymin, xmax, ymax``.
    start, goal
        ``(2,)`` points.
    obstacles
        All obstacles, grids included as rectangles.
    grid
        The occupancy grid when the scenario has one.
    encoding
        The encoding the scenario was made for.
    nodes
        Free nodes of the rotated-frame segment encoding, N - 1 for N segments (paper 003's
        "chromosome length", 12 on the 20 x 20 maps).
    description, path
        Free text and the file it came from.
    """

    name: str
    bounds: NDArray[np.float64]
    start: NDArray[np.float64]
    goal: NDArray[np.float64]
    obstacles: Obstacles2D
    grid: GridMap | None = None
    encoding: str = "spline"
    nodes: int = 12
    description: str = ""
    path: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def straight_distance(self) -> float:
        return float(np.linalg.norm(self.goal - self.start))

    @cached_property
    def world(self) -> Obstacles2D:
        """The obstacles plus four frame rectangles around the bounds, so that leaving the
        map is a collision (what encodings, exact planners and metrics judge paths against)."""
        x0, y0, x1, y1 = (float(v) for v in self.bounds)
        m = max(x1 - x0, y1 - y0)
        frame = np.array(
            [
                [x0 - m, y0 - m, x1 + m, y0],
                [x0 - m, y1, x1 + m, y1 + m],
                [x0 - m, y0, x0, y1],
                [x1, y0, x1 + m, y1],
            ]
        )
        o = self.obstacles
        return Obstacles2D(
            circles=o.circles,
            rectangles=np.concatenate([o.rectangles, frame]),
            polygons=o.polygons,
        )


def scenario_path(name_or_path: str | Path, folder: Path = SCENARIO_DIR) -> Path:
    """The file of a scenario shipped in ``folder`` by name (``circles-1``) or the path itself."""
    p = Path(name_or_path)
    if p.exists() or p.suffix:
        return p
    cand = folder / f"{name_or_path}.json"
    return cand if cand.exists() else p


def available_scenarios(folder: Path = SCENARIO_DIR) -> list[str]:
    """Names of the scenarios shipped in ``folder`` (default ``assets/scenarios``)."""
    return sorted(p.stem for p in folder.glob("*.json"))


def load_scenario(name_or_path: str | Path) -> Scenario:
    """Read and validate a scenario file (or a shipped scenario by name)."""
    path = scenario_path(name_or_path)
    text = path.read_text()
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"not valid JSON: {exc.msg}", path=path, line=exc.lineno) from None
    return scenario_from_dict(data, path=path)


def _num_array(value: Any, shape: tuple[int, ...], where: str, path: Any) -> NDArray[np.float64]:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"expected numbers, got {value!r}", path=path, field=where) from None
    if arr.ndim != len(shape) or any(
        s != -1 and a != s for a, s in zip(arr.shape, shape, strict=False)
    ):
        want = " x ".join("n" if s == -1 else str(s) for s in shape)
        raise InputError(
            f"expected an array of shape {want}, got {value!r}", path=path, field=where
        )
    if not np.all(np.isfinite(arr)):
        raise InputError("values must be finite", path=path, field=where)
    return arr


def _grid_from(obj: dict[str, Any], where: str, path: Any) -> GridMap:
    rows = obj.get("rows")
    if not isinstance(rows, list) or not rows or not all(isinstance(r, str) for r in rows):
        raise InputError("a grid needs 'rows', a list of strings", path=path, field=f"{where}.rows")
    width = len(rows[0])
    for k, r in enumerate(rows):
        if len(r) != width:
            raise InputError(
                f"row {k} has {len(r)} cells, row 0 has {width}", path=path, field=f"{where}.rows"
            )
        bad = set(r) - {"#", "."}
        if bad:
            raise InputError(
                f"row {k} has characters {sorted(bad)}; use '#' (occupied) and '.' (free)",
                path=path,
                field=f"{where}.rows",
            )
    occ = np.array([[c == "#" for c in r] for r in rows[::-1]], dtype=bool).T  # (nx, ny)
    origin = _num_array(obj.get("origin", [0.0, 0.0]), (2,), f"{where}.origin", path)
    cell = float(_num_array(obj.get("cell", 1.0), (), f"{where}.cell", path))
    if cell <= 0:
        raise InputError("cell size must be positive", path=path, field=f"{where}.cell")
    occ.setflags(write=False)
    return GridMap(occupied=occ, origin=(float(origin[0]), float(origin[1])), cell=cell)


def _obstacles_from(obstacles: Any, path: Any) -> tuple[Obstacles2D, GridMap | None]:
    """The scenario's ``obstacles`` list (module docstring) validated: the obstacles (a grid's
    occupied cells as rectangles) and the grid itself when there is one (at most one).

    Raises
    ------
    InputError
        Naming the obstacle's field, for a malformed or unknown obstacle.
    """
    circles, rects, polys = [], [], []
    grid: GridMap | None = None
    if not isinstance(obstacles, list):
        raise InputError("expected a list of obstacles", path=path, field="obstacles")
    for k, ob in enumerate(obstacles):
        where = f"obstacles[{k}]"
        if not isinstance(ob, dict):
            raise InputError("an obstacle must be an object", path=path, field=where)
        kind = ob.get("type")
        if kind == "circle":
            c = _num_array(ob.get("center"), (2,), f"{where}.center", path)
            r = float(_num_array(ob.get("radius"), (), f"{where}.radius", path))
            if r <= 0:
                raise InputError("radius must be positive", path=path, field=f"{where}.radius")
            circles.append([c[0], c[1], r])
        elif kind == "rectangle":
            lo = _num_array(ob.get("min"), (2,), f"{where}.min", path)
            hi = _num_array(ob.get("max"), (2,), f"{where}.max", path)
            if np.any(hi <= lo):
                raise InputError(
                    "rectangle needs min < max in x and y", path=path, field=f"{where}.max"
                )
            rects.append([lo[0], lo[1], hi[0], hi[1]])
        elif kind == "polygon":
            v = _num_array(ob.get("vertices"), (-1, 2), f"{where}.vertices", path)
            if len(v) >= 2 and np.all(v[0] == v[-1]):
                v = v[:-1]  # an explicitly closed ring
            if not polygon_is_simple(v):
                raise InputError(
                    "polygon is not simple (self-intersecting, fewer than 3 distinct vertices, "
                    "or zero area)",
                    path=path,
                    field=f"{where}.vertices",
                )
            polys.append(v)
        elif kind == "grid":
            if grid is not None:
                raise InputError("at most one grid per scenario", path=path, field=where)
            grid = _grid_from(ob, where, path)
            rects.extend(grid_to_rectangles(grid.occupied, grid.origin, grid.cell).tolist())
        else:
            raise InputError(
                f"unknown obstacle type {kind!r}; use one of {', '.join(OBSTACLE_TYPES)}",
                path=path,
                field=f"{where}.type",
            )
    return Obstacles2D(
        circles=np.array(circles).reshape(-1, 3),
        rectangles=np.array(rects).reshape(-1, 4),
        polygons=tuple(polys),
    ), grid


def scenario_from_dict(data: Any, *, path: Any = None) -> Scenario:
    """Validate a scenario given as a parsed JSON object (see the module docstring)."""
    if not isinstance(data, dict):
        raise InputError("a scenario must be a JSON object", path=path)
    for key in ("bounds", "start", "goal"):
        if key not in data:
            raise InputError("missing required field", path=path, field=key)
    bounds = _num_array(data["bounds"], (4,), "bounds", path)
    if bounds[2] <= bounds[0] or bounds[3] <= bounds[1]:
        raise InputError(
            "bounds must be [xmin, ymin, xmax, ymax] with min < max", path=path, field="bounds"
        )
    start = _num_array(data["start"], (2,), "start", path)
    goal = _num_array(data["goal"], (2,), "goal", path)
    obs, grid = _obstacles_from(data.get("obstacles", []), path)
    for key, p in (("start", start), ("goal", goal)):
        if p[0] < bounds[0] or p[0] > bounds[2] or p[1] < bounds[1] or p[1] > bounds[3]:
            raise InputError(
                f"{key} {p.tolist()} is outside the bounds {bounds.tolist()}", path=path, field=key
            )
        if obs.n_obstacles and bool(obs.contains(p)):
            raise InputError(f"{key} {p.tolist()} is inside an obstacle", path=path, field=key)
    encoding = data.get("encoding", "grid" if grid is not None else "spline")
    if encoding not in ENCODINGS:
        raise InputError(
            f"unknown encoding {encoding!r}; use one of {', '.join(ENCODINGS)}",
            path=path,
            field="encoding",
        )
    nodes = data.get("nodes", 12)
    if not isinstance(nodes, int) or isinstance(nodes, bool) or nodes < 1:
        raise InputError("nodes must be an integer >= 1", path=path, field="nodes")
    for arr in (bounds, start, goal):
        arr.setflags(write=False)
    name = data.get("name") or (Path(path).stem if path is not None else "scenario")
    known = {"name", "description", "bounds", "start", "goal", "obstacles", "encoding", "nodes"}
    return Scenario(
        name=str(name),
        bounds=bounds,
        start=start,
        goal=goal,
        obstacles=obs,
        grid=grid,
        encoding=encoding,
        nodes=nodes,
        description=str(data.get("description", "")),
        path=None if path is None else str(path),
        extra={k: v for k, v in data.items() if k not in known},
    )
