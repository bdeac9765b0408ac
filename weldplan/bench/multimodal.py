"""``weldplan bench planar --protocols multimodal``: ParaPA's k distinct paths on the 20 x 20 maps.

For each map and seed, one multimodal run (003 4.3-4.4, :func:`plan_multimodal`) and, beside
it, the single-best ParaPA with the same particles and iterations: how often all k paths are
collision-free and pairwise distinct, each rank's mean length and gap to the exact optimum,
the repairs of Algorithm 2 and the times. Called from :mod:`weldplan.bench.planar`.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

MAPS = [f"map20-{i}" for i in range(1, 8)]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--runs-mm", type=int, default=5, help="seeds per map (multimodal)")
    parser.add_argument("--k-mm", type=int, default=3, help="paths per run (multimodal)")
    parser.add_argument("--iters-mm", type=int, default=200, help="iterations (multimodal)")
    parser.add_argument("--maps-mm", default=",".join(MAPS), help="maps (multimodal)")


def _one(task: tuple) -> dict:
    from weldplan.planar.multimodal import DEFAULT_SWARMS, PAPER_NP, plan_multimodal
    from weldplan.planar.scenarios import load_scenario
    from weldplan.planar.solve import PlanarSettings, solve

    name, k, iters, seed = task
    sc = load_scenario(name)
    r = plan_multimodal(sc, k, iterations=iters, rng=seed, with_optimum=False)
    single = PlanarSettings(
        pop_size=DEFAULT_SWARMS * PAPER_NP,
        max_iter=iters,
        with_optimum=False,
        optimizer_params={"n_swarms": DEFAULT_SWARMS},
        as_printed=True,  # the paper's ParaPA alone, as the multimodal planner is
    )
    s = solve(sc, "parapa", single, rng=seed)
    return {
        "map": name,
        "seed": seed,
        "result": r.to_json(),
        "single": s.length,
        "single_ok": s.success,
        "single_s": s.seconds,
    }


def protocol_multimodal(args: argparse.Namespace, out: Path) -> list[str]:
    from weldplan.planar.multimodal import DEFAULT_SWARMS, PAPER_NP, MultimodalResult
    from weldplan.planar.scenarios import load_scenario
    from weldplan.planar.solve import exact_optimum
    from weldplan.viz.planar import plot_paths

    k = args.k_mm
    maps = [m for m in args.maps_mm.split(",") if m]
    tasks = [(m, k, args.iters_mm, s) for m in maps for s in range(args.runs_mm)]
    t0 = time.perf_counter()
    if args.jobs > 1:
        with ProcessPoolExecutor(max_workers=args.jobs) as ex:
            rows = list(ex.map(_one, tasks, chunksize=1))
    else:
        rows = [_one(t) for t in tasks]
    lines = [
        f"## Paper 003 4.3-4.4: {k} distinct paths from one ParaPA run",
        "",
        f"{DEFAULT_SWARMS} swarms x NP = {PAPER_NP}, {args.iters_mm} iterations, rotated-frame "
        f"segments, {args.runs_mm} seeds per map. 'all ok' = runs whose {k} paths are all "
        "collision-free and pairwise in different homology classes; 'free' = collision-free "
        f"paths out of {k} x runs; path i = mean length of the i-th shortest (over collision-free "
        "ones) and its gap to the exact optimum (the global shortest path: paths 2 and 3 must "
        "pass some obstacle on the other side, so their gap includes that detour); repairs = "
        "Algorithm 2 on abandoned hosts per run (mean). Beside: the single-best ParaPA with "
        "the same particles and iterations (mean length over successful runs, mean time), and "
        "the time ratio multimodal / single.",
        "",
        "| map | exact | all ok | free | "
        + " | ".join(f"path {i + 1} (gap)" for i in range(k))
        + " | repairs | time s | ParaPA single | single time s | time ratio |",
        "|---|---|---|---|" + "---|" * k + "---|---|---|---|---|",
    ]
    for m in maps:
        rr = [r for r in rows if r["map"] == m]
        res = [MultimodalResult.from_json(r["result"]) for r in rr]
        sc = load_scenario(m)
        ex = exact_optimum(sc, "segments")
        all_ok = sum(r.n_success == k and r.all_distinct for r in res)
        free = sum(r.n_success for r in res)
        cells = []
        for i in range(k):
            L = [r.lengths[i] for r in res if r.success[i]]
            cells.append(
                f"{np.mean(L):.3f} ({100 * (np.mean(L) / ex.length - 1):+.1f} %)" if L else "-"
            )
        single = [r["single"] for r in rr if r["single_ok"]]
        t_mm = float(np.mean([r.seconds for r in res]))
        t_s = float(np.mean([r["single_s"] for r in rr]))
        lines.append(
            f"| {m} | {ex.length:.3f} | {all_ok}/{len(res)} | {free}/{k * len(res)} | "
            + " | ".join(cells)
            + f" | {np.mean([r.repairs for r in res]):.1f} | {t_mm:.2f} | "
            + (f"{np.mean(single):.3f}" if single else "-")
            + f" | {t_s:.2f} | {t_mm / t_s:.2f} |"
        )
        best = max(res, key=lambda r: (r.n_success == k and r.all_distinct, -sum(r.lengths)))
        plot_paths(
            sc,
            {
                f"path {i + 1} {best.lengths[i]:.3f}"
                + ("" if best.success[i] else " collides"): best.path_array(i)
                for i in range(k)
            },
            out / f"multimodal-{m}.png",
            exact=ex.points_array,
            title=f"{m}: {k} multimodal ParaPA paths (seed {best.seed}), exact {ex.length:.3f}",
        )
    lines += [
        "",
        f"Wall time of the protocol: {time.perf_counter() - t0:.1f} s with {args.jobs} "
        "processes. PNGs: `multimodal-<map>.png` (the best run of each map).",
        "",
    ]
    return lines
