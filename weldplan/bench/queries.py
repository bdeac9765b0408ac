"""``weldplan bench queries MAP SCEN``: every query of a Moving AI ``.scen`` file, the way
pathfinding researchers compare planners.

``MAP`` is a Polyanya navigation mesh (``.mesh`` v2) or a Moving AI grid (``.map``):

* ``--metric any-angle`` (the default on a ``.mesh``): Polyanya
  (:mod:`weldplan.planar.polyanya`). On a ``.map`` the grid is first made a navigation mesh
  (:func:`weldplan.planar.navmesh.grid_navmesh`, cell ``(x, y)`` = ``[x, x + 1] x [y, y + 1]``).
* ``--metric octile`` (the default on a ``.map``): 8-connected grid paths without corner
  cutting (:func:`weldplan.planar.exact.grid_lengths`), the Moving AI benchmark rules.

Coordinates: Moving AI ``.scen`` rows give integer ``x y`` per endpoint. For the octile metric
they are cells (``x`` the column, ``y`` the row as written in the ``.map``). For the any-angle
metric they are used as they are, as points of the mesh plane, like the authors' Polyanya
scenario runner: on a grid converted here that is the *corner* of cell ``(x, y)`` (its
lower-left corner in the mesh's ``x, y`` frame), not its centre. Checked on
``../shared/data/meshmaps/arena.mesh.anyangle.scen``: 160/160 equal with raw points on
``arena.mesh`` (cell centres, ``x + 0.5``, give other lengths).

The report: how many lengths equal the file's (within 1e-6 relative, or one unit of the last
digit the file prints: :func:`summary`), are shorter, are longer,
have no path; the median, p95 and max milliseconds per query; the load time and the total. A
length that differs from the file is a result, not an error: the command exits 0 when every
query ran. ``--csv F`` writes ``index,sx,sy,gx,gy,reference,length,ms`` per query (``length``
NaN where there is no path). The first query on a fresh install also compiles the search
(numba, cached on disk afterwards); it is timed apart as the warm-up, outside the per-query
figures and inside the total.
"""

from __future__ import annotations

import argparse
import csv
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError

HELP = "run every query of a Moving AI .scen on a Polyanya .mesh or a Moving AI .map"

log = logging.getLogger(__name__)

#: relative tolerance under which a length equals the file's
REL_TOL = 1e-6


@dataclass(frozen=True)
class Queries:
    """The rows of a ``.scen`` file: ``start, goal (n, 2) float``, ``reference (n,)`` lengths,
    ``resolution (n,)`` one unit in the last digit each length is printed with, ``line (n,)``
    their line numbers."""

    start: NDArray[np.float64]
    goal: NDArray[np.float64]
    reference: NDArray[np.float64]
    resolution: NDArray[np.float64]
    line: NDArray[np.int64]


def read_queries(path: str | Path) -> Queries:
    """Read a Moving AI ``.scen`` (``version 1``: bucket, map, width, height, sx, sy, gx, gy,
    length; tab or space separated).

    Raises
    ------
    InputError
        Naming the file, line and field of the first bad row.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", path=path) from None
    names = ("start x", "start y", "goal x", "goal y", "length")
    rows, lines, res = [], [], []
    for k, line in enumerate(text.splitlines(), 1):
        if not line.strip() or line.startswith("version"):
            continue
        f = line.split("\t") if "\t" in line else line.split()
        if len(f) < 9:
            raise InputError(f"expected 9 fields, found {len(f)}", path=path, line=k)
        vals = []
        for name, tok in zip(names, f[4:9], strict=True):
            try:
                vals.append(float(tok))
            except ValueError:
                raise InputError(f"not a number: {tok!r}", path=path, line=k, field=name) from None
        rows.append(vals)
        lines.append(k)
        digits = f[8].strip().lower().split("e")[0].partition(".")[2]
        # %g-style files print 6 significant digits ("1" for 1.00000)
        sig = 10.0 ** (math.floor(math.log10(max(abs(vals[4]), 1e-300))) - 5)
        res.append(min(10.0 ** -len(digits), sig))
    if not rows:
        raise InputError("no queries", path=path)
    a = np.array(rows, dtype=np.float64)
    return Queries(a[:, 0:2], a[:, 2:4], a[:, 4], np.array(res), np.array(lines, dtype=np.int64))


@dataclass(frozen=True)
class QueryRun:
    """Lengths and times of a run: ``length (n,)`` (``nan`` where no path), ``ms (n,)``;
    ``load_s`` (reading the map and building what the metric needs), ``warmup_s`` (the first
    query's extra cost: compilation on a fresh install), ``total_s`` (everything)."""

    queries: Queries
    length: NDArray[np.float64]
    ms: NDArray[np.float64]
    load_s: float
    warmup_s: float
    total_s: float
    metric: str


def run_queries(map_path: str | Path, queries: Queries, metric: str) -> QueryRun:
    """Answer every query on ``map_path`` with ``metric`` (``"any-angle"`` or ``"octile"``)."""
    t0 = time.perf_counter()
    map_path = Path(map_path)
    is_mesh = map_path.suffix == ".mesh"
    n = len(queries.reference)
    length = np.full(n, np.nan)
    ms = np.zeros(n)
    if metric == "octile":
        if is_mesh:
            raise InputError("the octile metric needs a grid (.map), not a mesh", path=map_path)
        from weldplan.planar.exact import grid_graph, grid_lengths, read_movingai_map

        free = read_movingai_map(map_path)
        graph = grid_graph(free)
        load = time.perf_counter() - t0
        S = queries.start.astype(np.int64)
        T = queries.goal.astype(np.int64)
        inside = np.all((S >= 0) & (S < free.shape) & (T >= 0) & (T < free.shape), axis=1)
        for k in range(n):
            t = time.perf_counter()
            if inside[k] and free[tuple(S[k])] and free[tuple(T[k])]:
                d = float(grid_lengths(free, S[k : k + 1], T[k : k + 1], graph=graph)[0])
                length[k] = d if math.isfinite(d) else np.nan
            ms[k] = 1e3 * (time.perf_counter() - t)
        return QueryRun(queries, length, ms, load, 0.0, time.perf_counter() - t0, metric)
    from weldplan.planar.navmesh import NavMesh, grid_navmesh
    from weldplan.planar.polyanya import Polyanya, warm_up

    if is_mesh:
        mesh = NavMesh.read(map_path)
    else:
        from weldplan.planar.exact import read_movingai_map

        mesh = grid_navmesh(read_movingai_map(map_path))
    planner = Polyanya(mesh)
    load = time.perf_counter() - t0
    warm = warm_up()  # compiles on a fresh install, loads numba's cache otherwise
    for k in range(n):
        t = time.perf_counter()
        d = planner.distance(queries.start[k], queries.goal[k])
        ms[k] = 1e3 * (time.perf_counter() - t)
        length[k] = d if math.isfinite(d) else np.nan
    return QueryRun(queries, length, ms, load, warm, time.perf_counter() - t0, metric)


def summary(run: QueryRun) -> dict[str, float]:
    """Counts (equal, shorter, longer, no path) and times. Equal: within :data:`REL_TOL`
    relative, or within one unit of the last digit the file prints (Moving AI files print
    lengths to 6 significant digits, ``5.24264`` for 5.2426407, coarser than 1e-6)."""
    ref = run.queries.reference
    L = run.length
    found = np.isfinite(L)
    tol = np.maximum(REL_TOL * np.abs(ref), run.queries.resolution)
    eq = found & (np.abs(L - ref) <= tol)
    return {
        "queries": float(len(L)),
        "equal": float(eq.sum()),
        "shorter": float((found & ~eq & (L < ref)).sum()),
        "longer": float((found & ~eq & (L > ref)).sum()),
        "no_path": float((~found).sum()),
        "median_ms": float(np.median(run.ms)),
        "p95_ms": float(np.percentile(run.ms, 95)),
        "max_ms": float(run.ms.max()),
        "queries_s": float(run.ms.sum() / 1e3),
        "load_s": run.load_s,
        "warmup_s": run.warmup_s,
        "total_s": run.total_s,
    }


def write_csv(run: QueryRun, path: str | Path) -> None:
    """One row per query: ``index,sx,sy,gx,gy,reference,length,ms``."""
    q = run.queries
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "sx", "sy", "gx", "gy", "reference", "length", "ms"])
        for k in range(len(q.reference)):
            w.writerow(
                [
                    k,
                    f"{q.start[k, 0]:g}",
                    f"{q.start[k, 1]:g}",
                    f"{q.goal[k, 0]:g}",
                    f"{q.goal[k, 1]:g}",
                    repr(float(q.reference[k])),
                    "nan" if not np.isfinite(run.length[k]) else repr(float(run.length[k])),
                    f"{run.ms[k]:.4f}",
                ]
            )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("map", help="a Polyanya .mesh (v2) or a Moving AI .map")
    parser.add_argument("scen", help="a Moving AI .scen file of queries on it")
    parser.add_argument(
        "--metric",
        choices=("any-angle", "octile"),
        default=None,
        help="any-angle (Polyanya; the default on a .mesh) or octile (8-connected grid, no "
        "corner cutting; the default on a .map)",
    )
    parser.add_argument("--csv", default=None, help="write one row per query to this file")


def run(args: argparse.Namespace) -> int:
    map_path = Path(args.map)
    if map_path.suffix not in (".mesh", ".map"):
        raise InputError("expected a .mesh or .map file", path=map_path)
    if not map_path.is_file():
        raise InputError("no such file", path=map_path)
    metric = args.metric or ("any-angle" if map_path.suffix == ".mesh" else "octile")
    queries = read_queries(args.scen)
    result = run_queries(map_path, queries, metric)
    s = summary(result)
    print(f"{map_path.name}, {Path(args.scen).name}: {int(s['queries'])} queries, {metric}")
    print(
        f"  equal to the file's (within {REL_TOL:g} relative or its printed digits): "
        f"{int(s['equal'])}, "
        f"shorter: {int(s['shorter'])}, longer: {int(s['longer'])}, no path: {int(s['no_path'])}"
    )
    print(
        f"  per query: median {s['median_ms']:.3f} ms, p95 {s['p95_ms']:.3f} ms, "
        f"max {s['max_ms']:.3f} ms; queries {s['queries_s']:.2f} s"
    )
    print(
        f"  load {s['load_s']:.2f} s, first-call warm-up {s['warmup_s']:.2f} s, "
        f"total {s['total_s']:.2f} s"
    )
    if args.csv:
        write_csv(result, args.csv)
        print(f"  wrote {args.csv}")
    return 0
