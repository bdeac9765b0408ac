"""``weldplan bench planar --protocols exact``: the exact planners against third-party data
(:mod:`weldplan.bench.planar`)."""

from __future__ import annotations

import argparse
import logging
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)


def _units(err: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Errors over one unit of the 6th significant digit of ``ref`` (at least 1e-4)."""
    res = 10.0 ** (np.floor(np.log10(np.maximum(ref, 1e-12))) - 5)
    return err / np.maximum(1e-4, res)


def _astar_map(task: tuple) -> dict:
    from weldplan.planar.exact import (
        astar_grid,
        grid_graph,
        grid_lengths,
        read_movingai_map,
        read_scen,
    )

    folder, name, seconds = task[:3]
    d_seconds = task[3] if len(task) > 3 else None
    free = read_movingai_map(Path(folder) / f"{name}.map")
    sc = read_scen(Path(folder) / f"{name}.map.scen")
    # the Python heap A* on the queries in file order until ``seconds`` run out
    t0 = time.perf_counter()
    c0 = time.process_time()
    errs = []
    for k in range(len(sc.length)):
        if time.perf_counter() - t0 > seconds:
            break
        errs.append(abs(astar_grid(free, sc.start[k], sc.goal[k]).length - sc.length[k]))
    done = len(errs)
    err = np.asarray(errs)
    a_units = _units(err, sc.length[:done]) if done else np.zeros(0)
    a_cpu = time.process_time() - c0
    a_seconds = time.perf_counter() - t0
    # every query: the same graph searched by scipy's compiled Dijkstra
    t1 = time.perf_counter()
    c1 = time.process_time()
    G = grid_graph(free)
    n_q = len(sc.length)
    # strided order, so that a time-boxed run still covers every bucket
    order = np.argsort(np.arange(n_q) % 10, kind="stable")
    L = np.full(n_q, np.nan)
    for k in order:
        if d_seconds is not None and time.perf_counter() - t1 > d_seconds:
            break
        L[k] = grid_lengths(free, sc.start[k : k + 1], sc.goal[k : k + 1], graph=G)[0]
    got = np.isfinite(L) | np.isinf(L)
    got &= ~np.isnan(L)
    d_err = np.abs(L[got] - sc.length[got])
    d_units = _units(d_err, sc.length[got])
    return {
        "map": name,
        "queries": len(sc.length),
        "done": done,
        "worst_abs": float(err.max(initial=0.0)),
        "worst_units": float(a_units.max(initial=0.0)),
        "match": int(np.sum(a_units <= 1.0)),
        "seconds": a_seconds,
        "cpu_per_query": a_cpu / max(done, 1),
        "d_match": int(np.sum(d_units <= 1.0)),
        "d_worst_abs": float(d_err.max(initial=0.0)),
        "d_worst_units": float(d_units.max(initial=0.0)),
        "d_seconds": time.perf_counter() - t1,
        "d_done": int(got.sum()),
        "d_cpu_per_query": (time.process_time() - c1) / max(int(got.sum()), 1),
    }


def protocol_exact(args: argparse.Namespace, out: Path) -> list[str]:
    data = Path(args.data) if args.data else Path(__file__).resolve().parents[3] / "shared" / "data"
    lines = ["## Exact planners against third-party data", ""]
    if not (data / "movingai").exists():
        return lines + [f"Shared data not found at {data}; skipped.", ""]
    names = ["arena", "random512-10-0", "maze512-32-9"]
    d_sec = getattr(args, "dijkstra_seconds", None)
    tasks = [(str(data / "movingai"), n, args.exact_seconds, d_sec) for n in names]
    if args.jobs > 1:
        with ProcessPoolExecutor(max_workers=min(args.jobs, 3)) as ex:
            res = list(ex.map(_astar_map, tasks))
    else:
        res = [_astar_map(t) for t in tasks]
    lines += [
        "A* (8-connected, octile, no corner cutting) against the optimal lengths of the "
        "Moving AI scenario files. The files print 6 significant digits, so an absolute "
        "1e-4 is unattainable for lengths >= 100: 'error in units' is the error over "
        "max(1e-4, one unit of the last printed digit), <= 1 is a match. The Python heap "
        f"A* runs the queries in file order for {args.exact_seconds:.0f} s a map; every "
        "query (in a strided order, within `--dijkstra-seconds` when given) is searched "
        "on the same graph (`grid_graph`: the same moves and "
        "corner rule) by scipy's compiled Dijkstra (`grid_lengths`). CPU seconds per query.",
        "",
        "| map | queries | A* checked | A* matches | A* max abs error | A* max units "
        "| A* CPU s/query | Dijkstra matches / checked | Dijkstra max abs error "
        "| Dijkstra max units "
        "| Dijkstra CPU s/query | seconds (A*, Dijkstra) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in res:
        lines.append(
            f"| {r['map']} | {r['queries']} | {r['done']} | {r['match']} | "
            f"{r['worst_abs']:.2e} | {r['worst_units']:.2f} | {r['cpu_per_query']:.4f} | "
            f"{r['d_match']}/{r['d_done']} of {r['queries']} | {r['d_worst_abs']:.2e} | "
            f"{r['d_worst_units']:.2f} | {r['d_cpu_per_query']:.4f} | "
            f"{r['seconds']:.0f}, {r['d_seconds']:.0f} |"
        )
    lines += _arena_lines(data)
    aurora = data / "meshmaps" / "aurora.mesh"
    if aurora.exists():
        lines += _aurora_lines(aurora, args.mesh_seconds)
    return lines


def _arena_lines(data: Path) -> list[str]:
    """The visibility graph on the Polyanya arena mesh against the same map as a Moving AI
    grid (the section's report lines; none without the mesh file)."""
    from weldplan.geometry.obstacles2d import Obstacles2D, grid_to_rectangles
    from weldplan.planar.exact import MeshFreeSpace, VisibilityGraph, read_movingai_map, read_scen

    mesh_file = data / "meshmaps" / "arena.mesh"
    if not mesh_file.exists():
        return []
    t0 = time.perf_counter()
    mesh = MeshFreeSpace.read(mesh_file)
    free = read_movingai_map(data / "movingai" / "arena.map")
    sc = read_scen(data / "meshmaps" / "arena.mesh.scen")
    vm = VisibilityGraph(mesh)
    vg = VisibilityGraph(Obstacles2D(rectangles=grid_to_rectangles(~free)))
    Lm = np.array(
        [vm.shortest_path(s + 0.5, g + 0.5).length for s, g in zip(sc.start, sc.goal, strict=True)]
    )
    Lg = np.array(
        [vg.shortest_path(s + 0.5, g + 0.5).length for s, g in zip(sc.start, sc.goal, strict=True)]
    )
    ratio = sc.length / Lm
    low = sc.length / OCTILE_OVER_EUCLID
    return [
        "",
        "Visibility graph on the Polyanya arena mesh (v2) and on the same map as a Moving "
        "AI grid (rectangles), start and goal at cell centres. The `.scen` lengths shipped "
        "with the mesh are the octile grid lengths (identical to the Moving AI file), not "
        "any-angle optima, so they bound the any-angle length from above; the two "
        "independent free-space descriptions must agree.",
        "",
        f"- queries: {len(Lm)}; mesh vs grid visibility graph: max |difference| "
        f"{np.max(np.abs(Lm - Lg)):.2e}, within 1e-3 for "
        f"{100 * np.mean(np.abs(Lm - Lg) <= 1e-3):.1f} %",
        f"- any-angle <= octile (+1e-4) for {100 * np.mean(Lm <= sc.length + 1e-4):.1f} %; "
        f"octile / any-angle ratio min {ratio.min():.4f}, mean {ratio.mean():.4f}, "
        f"max {ratio.max():.4f}",
        f"- any-angle >= octile / 1.0824 (octile is at most 8.24 % above Euclidean) for "
        f"{100 * np.mean(Lm >= low - 1e-4):.1f} %",
        f"- mesh: {len(mesh.vertices_xy)} vertices, {len(vm.nodes)} turning points; "
        f"{time.perf_counter() - t0:.1f} s in all",
        "",
    ]


#: the largest ratio of the octile distance to the Euclidean one, sqrt(4 - 2 sqrt(2))
OCTILE_OVER_EUCLID = float(np.sqrt(4.0 - 2.0 * np.sqrt(2.0)))


def _aurora_lines(mesh_file: Path, seconds: float) -> list[str]:
    """Aurora (34,707 vertices): bounded, lazy visibility-graph queries on a time budget."""
    from weldplan.errors import PlanningError
    from weldplan.planar.exact import MeshFreeSpace, mesh_shortest_path_bounded, read_scen

    t0 = time.perf_counter()
    mesh = MeshFreeSpace.read(mesh_file)
    sc = read_scen(Path(str(mesh_file) + ".scen"))
    # the first query of every bucket, buckets in increasing length, then the rest
    first = np.unique(sc.bucket, return_index=True)[1]
    order = np.concatenate([first, np.setdiff1d(np.arange(len(sc.length)), first)])
    L, ref, buckets, cpu = [], [], [], []
    over = 0
    t1 = time.perf_counter()
    for k in order:
        if time.perf_counter() - t1 > seconds:
            break
        c0 = time.process_time()
        bound = sc.length[k] * (1 + 1e-6) + 1e-3
        try:
            r = mesh_shortest_path_bounded(mesh, sc.start[k] + 0.5, sc.goal[k] + 0.5, bound)
            L.append(r.length)
        except PlanningError:  # longer than the octile length: a violation
            L.append(np.inf)
            over += 1
        cpu.append(time.process_time() - c0)
        ref.append(sc.length[k])
        buckets.append(int(sc.bucket[k]))
    La, Ra = np.array(L), np.array(ref)
    n = len(La)
    if n == 0:
        return ["", "aurora.mesh: no query finished within the time budget.", ""]
    ratio = Ra / La
    return [
        "",
        f"Polyanya aurora mesh ({len(mesh.vertices_xy)} vertices, {len(mesh.edge_a)} boundary "
        f"edges): no grid of this map is in the shared data, so only the bounds are checked. "
        "Each query searches the visibility graph of the corner vertices inside the ellipse "
        "of paths no longer than the `.scen` (octile) length, on the mesh cropped to it, "
        "with neighbours found lazily at expansion (A*, `mesh_shortest_path_bounded`): exact "
        "whenever the any-angle length is within that bound, and a reported violation "
        f"otherwise. Time budget {seconds:.0f} s; queries taken one per bucket in increasing "
        "length first.",
        "",
        f"- queries checked: {n} of {len(sc.length)} (buckets {min(buckets)}-{max(buckets)}; "
        f"octile lengths up to {Ra.max():.1f}); CPU s per query mean {np.mean(cpu):.2f}, "
        f"max {np.max(cpu):.2f}; {time.perf_counter() - t0:.0f} s in all",
        f"- any-angle <= octile (+1e-4): {int(np.sum(La <= Ra + 1e-4))}/{n} "
        f"({over} found no path within the octile length)",
        f"- any-angle >= octile / 1.0824: {int(np.sum(La >= Ra / OCTILE_OVER_EUCLID - 1e-4))}/{n}",
        f"- octile / any-angle ratio min {ratio.min():.4f}, mean {ratio.mean():.4f}, "
        f"max {ratio.max():.4f}",
        "",
    ]
