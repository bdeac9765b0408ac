"""``weldplan bench tour --protocols anyangle``: the default tour pipeline beside paper 002 as
printed, both measured against the exact optimal tour (Held-Karp over Polyanya's any-angle
distances; see :mod:`weldplan.planar.tour_planner`)."""

from __future__ import annotations

import argparse
import logging
import time
from typing import Any

import numpy as np

log = logging.getLogger(__name__)


def _runs(task: Any, runs: int, **kw: Any) -> tuple[list, list[float], list[float]]:
    """``runs`` seeded calls of ``plan_tour`` with the wall and process CPU seconds of each."""
    from weldplan.planar.tour_planner import plan_tour

    out, wall, cpu = [], [], []
    for s in range(runs):
        t0, c0 = time.perf_counter(), time.process_time()
        out.append(plan_tour(task, "isma", rng=s, **kw))
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return out, wall, cpu


def anyangle_protocol(args: argparse.Namespace, tasks: list) -> list[str]:
    """Per map: the default pipeline and paper 002 as printed, ``args.runs`` seeds each, at
    ``args.pop`` x ``args.iters``; returns the report's lines."""
    from weldplan.bench.common import table
    from weldplan.planar.multigoal import build_tour_graph
    from weldplan.planar.polyanya import warm_up
    from weldplan.planar.tour_anyangle import build_anyangle_graph
    from weldplan.planar.tour_planner import ground_truth

    warm_up()  # numba's one-off compile stays out of the per-map figures
    rows = []
    for name, task in tasks:
        g = build_tour_graph(task)
        aa = build_anyangle_graph(task)
        t0 = time.perf_counter()
        ex_order, ex_len, ex_method = ground_truth(aa)
        hk_s = time.perf_counter() - t0
        common = {"anyangle": aa, "exact": (ex_order, ex_len), "pop_size": args.pop,
                  "max_iter": args.iters}  # fmt: skip
        once = (f"mesh {g.build_seconds:.2f} s, {aa.n_queries} Polyanya legs "
                f"{aa.build_seconds:.2f} s, HK {hk_s:.3f} s")  # fmt: skip
        for label, kw in (("as printed (002)", {"graph": g, "as_printed": True}),
                          ("default", {})):  # fmt: skip
            rs, wall, cpu = _runs(task, args.runs, **common, **kw)
            gaps = np.array([r.exact_gap for r in rs])
            own = np.array([r.stages[0][1] / ex_len - 1.0 for r in rs])
            rows.append([name, len(task.stops), label, f"{ex_len:.1f}",
                         f"{100 * own.mean():.2f} %",
                         f"{100 * gaps.mean():.2f} %", f"{100 * gaps.max():.2f} %",
                         f"{np.mean(wall):.3f}", f"{np.mean(cpu):.3f}",
                         f"{sum(r.collision_free for r in rs)}/{len(rs)}",
                         f"{sum(bool(r.legs_collision_free) for r in rs)}/{len(rs)}",
                         once if label == "default" else ""])  # fmt: skip
            log.info("%s %s: mean gap %.4f", name, label, gaps.mean())
    head = ["map", "stops", "pipeline", "exact optimum", "ISMA's own order gap",
            "mean gap", "worst gap", "wall s/run", "CPU s/run", "collision-free",
            "legs free", "once per map"]  # fmt: skip
    return [
        "## Any-angle leg costs: the default pipeline vs paper 002 as printed",
        "",
        table(head, rows),
        "",
        f"{args.runs} runs per row (seeds 0..{args.runs - 1}), ISMA {args.pop} x {args.iters}. "
        "Gaps are the returned (smoothed) path's to the exact optimal closed tour: Held-Karp "
        "over the Polyanya distances between the stops. 'ISMA's own order gap' is the "
        "optimiser's order before any polish, over its own costs' legs (mesh-edge as printed). "
        "Per run: ordering, legs, B-spline and the exact collision checks; the mesh, the "
        "Polyanya legs and Held-Karp are built once per map and shared (last column).",
    ]
