"""``weldplan planar tour SCENARIO``: multi-goal traversal on a triangular-mesh map (paper 002).

Orders the targets with each optimiser of ``--order-by`` (random keys; by default the best
order is polished once by the sequencer's 2-opt + Or-opt search, ``--no-polish`` for the
optimiser as printed) and with the exact sequencer, pulls the legs tight in their triangle
corridors (``--no-funnel`` keeps the mesh-edge legs), smooths the tour with a B-spline and prints
length, smoothed length, gap to the ground-truth order and time; ``--plot`` writes a PNG of
the map, mesh and tours.
"""

from __future__ import annotations

import argparse
import json
import sys

from weldplan.errors import WeldplanError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("planar tour")
    g.add_argument(
        "--order-by",
        default="isma,exact",
        help="tour: comma-separated optimisers ordering the targets, 'exact' for the sequencer",
    )
    g.add_argument("--max-edge", type=float, default=None, help="tour: mesh edge M (map units)")
    g.add_argument("--two-opt", action="store_true", help="tour: 2-opt decoding of the random keys")
    g.add_argument(
        "--no-polish",
        action="store_true",
        help="tour: the optimiser's order as printed (no final 2-opt/Or-opt polish)",
    )
    g.add_argument(
        "--no-funnel",
        action="store_true",
        help="tour: keep the mesh-edge legs (paper 002) instead of pulling them tight",
    )
    g.add_argument("--no-smooth", action="store_true", help="tour: keep the mesh polyline")


def run(args: argparse.Namespace) -> int:
    from weldplan.optim.registry import ALGORITHMS
    from weldplan.planar.multigoal import (
        PAPER_ITER,
        PAPER_POP,
        build_tour_graph,
        ground_truth,
        load_tour,
        plan_tour,
    )

    if len(args.more) != 1:
        raise WeldplanError("usage: weldplan planar tour SCENARIO [options]")
    algos = [a.strip().lower() for a in args.order_by.split(",") if a.strip()]
    for a in algos:
        if a != "exact" and a not in ALGORITHMS:
            raise WeldplanError(f"unknown algorithm '{a}' (field --order-by)")
    if args.max_edge is not None and args.max_edge <= 0:
        raise WeldplanError("--max-edge must be positive")
    task = load_tour(args.more[0])
    graph = build_tour_graph(task, args.max_edge)
    _, opt, _ = ground_truth(graph)
    results = []
    for a in algos:
        results.append(
            plan_tour(
                task,
                a,
                graph=graph,
                pop_size=args.pop or PAPER_POP,
                max_iter=args.iters or PAPER_ITER,
                two_opt=args.two_opt,
                polish=not args.no_polish,
                taut=not args.no_funnel,
                smooth=not args.no_smooth,
                optimum=opt,
                rng=args.seed,
            )
        )
    if args.json:
        sys.stdout.write(json.dumps([json.loads(r.to_json()) for r in results]) + "\n")
    else:
        m = graph.mesh
        sys.stdout.write(
            f"scenario {task.name}: {len(task.goals)} targets, mesh M = {m.max_edge:g} "
            f"({m.n_nodes} nodes, {m.n_cells} triangles, built in {graph.build_seconds:.2f} s)\n"
            f"{'order by':<12}{'tour':>12}{'smoothed':>12}{'gap':>9}{'time/s':>9}  free\n"
        )
        for r in results:
            sys.stdout.write(
                f"{r.algorithm:<12}{r.length:>12.3f}{r.smooth_length:>12.3f}"
                f"{100 * r.gap:>8.2f}%{r.seconds:>9.3f}  "
                f"{'yes' if r.collision_free else 'NO'}{'' if r.smoothed else ' (polyline)'}\n"
            )
    if args.plot:
        from weldplan.viz.tour import plot_tour

        plot_tour(
            task,
            {f"{r.algorithm} ({r.smooth_length:.1f})": r.points_array for r in results},
            args.plot,
            mesh=graph.mesh,
            title=f"{task.name}: ground-truth tour {opt:.1f}",
        )
    return 0
