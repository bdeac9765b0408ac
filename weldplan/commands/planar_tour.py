"""``weldplan planar tour SCENARIO``: multi-goal traversal on a planar map (paper 002).

Default pipeline: the stops are ordered over exact any-angle leg lengths (Polyanya between
every pair of stops) by each optimiser of ``--order-by`` (random keys), the best order is
polished once by the sequencer's 2-opt + Or-opt search (``--no-polish``: the optimiser's order),
the legs are Polyanya's shortest paths, and the tour is smoothed by a B-spline.
``--as-printed`` is paper 002 exactly: Dijkstra along the triangle mesh's edges, the optimiser's
order, the B-spline over the mesh-edge legs; ``--metric mesh`` keeps the mesh-edge costs with the
polish and the funnel (``--no-funnel``: mesh-edge legs). The summary names the pipeline, shows
the optimiser's own order beside what each stage changed, and the exact optimal tour (Held-Karp
over the any-angle distances) with every answer's gap to it; ``--plot`` writes a PNG.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING

from weldplan.errors import WeldplanError

if TYPE_CHECKING:
    from weldplan.planar.tour_settings import TourSettings


def add_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("planar tour")
    g.add_argument(
        "--order-by",
        default="isma,exact",
        help="tour: comma-separated optimisers ordering the targets, 'exact' for the sequencer",
    )
    g.add_argument("--max-edge", type=float, default=None, help="tour: mesh edge M (map units)")
    g.add_argument(
        "--metric",
        choices=["any-angle", "mesh"],
        default=None,
        help="tour: leg costs: exact any-angle (Polyanya; default) or mesh-edge Dijkstra "
        "(paper 002; the default with --as-printed or --no-funnel)",
    )
    g.add_argument("--two-opt", action="store_true", help="tour: 2-opt decoding of the random keys")
    g.add_argument(
        "--no-polish",
        action="store_true",
        help="tour: the optimiser's order as printed (no final 2-opt/Or-opt polish)",
    )
    g.add_argument(
        "--no-funnel",
        action="store_true",
        help="tour: mesh-edge legs (paper 002) instead of taut ones (implies --metric mesh)",
    )
    g.add_argument("--no-smooth", action="store_true", help="tour: keep the mesh polyline")


def _pipeline_line(r0) -> str:
    """Which pipeline the run used (as printed, default, or custom), one line."""
    if r0.pipeline == "as-printed":
        return (
            "pipeline   as printed (paper 002): mesh-edge Dijkstra costs -> optimiser's order "
            "-> B-spline over the mesh-edge legs\n"
        )
    if r0.pipeline == "default":
        return (
            "pipeline   default: any-angle costs (Polyanya) -> optimiser -> polish -> "
            "Polyanya legs -> B-spline (--as-printed: paper 002 alone)\n"
        )
    taut = r0.metric == "any-angle" or any(s[0] == "funnel" for s in r0.stages)
    return (
        f"pipeline   custom: {r0.metric} costs, polish {'on' if r0.polished else 'off'}, "
        f"{'taut' if taut else 'mesh-edge'} legs\n"
    )


def _summary(task, results, exact_len: float, exact_method: str, anyangle) -> str:
    head = f"scenario   {task.name}: {len(task.goals)} targets\n" + _pipeline_line(results[0])
    head += (
        f"exact optimum {exact_len:.3f} (Held-Karp over the any-angle distances, {exact_method}; "
        f"{anyangle.n_queries} Polyanya legs in {anyangle.build_seconds:.2f} s)\n"
    )
    lines = [head]
    for r in results:
        lines.append(
            f"\n{r.algorithm}: order {' '.join(map(str, r.order))}\n"
            "stage        length      gap  seconds  change\n"
        )
        prev = None
        for name, length, secs, note in r.stages:
            gap = 100 * (length / exact_len - 1.0)
            change = "" if prev is None else f"{100 * (length / prev - 1.0):+.2f} % "
            lines.append(f"{name:<9s} {length:10.3f} {gap:+7.2f} % {secs:8.3f}  {change}{note}\n")
            prev = length
        free = "yes" if r.collision_free else "NO"
        lines.append(
            f"returned  {r.smooth_length:10.3f} {100 * r.exact_gap:+7.2f} %  collision-free {free}"
            f"{'' if r.smoothed else ' (polyline)'}, ordering {r.seconds:.3f} s "
            f"(CPU {r.cpu_seconds:.3f} s)\n"
        )
    return "".join(lines)


def run(args: argparse.Namespace) -> int:
    from weldplan.planar.multigoal import build_tour_graph, load_tour
    from weldplan.planar.tour_anyangle import build_anyangle_graph
    from weldplan.planar.tour_planner import ground_truth, plan_tour

    algos = _algorithms(args)
    as_printed = bool(getattr(args, "as_printed", False))
    task = load_tour(args.more[0])
    anyangle = build_anyangle_graph(task)
    ex_order, ex_len, ex_method = ground_truth(anyangle)
    st = _tour_settings(args, as_printed)
    graph = build_tour_graph(task, args.max_edge) if st.resolved()[0] == "mesh" else None
    results = [
        plan_tour(task, a, st, graph=graph, anyangle=anyangle, exact=(ex_order, ex_len),
                  rng=args.seed)
        for a in algos
    ]  # fmt: skip
    if args.json:
        sys.stdout.write(json.dumps([json.loads(r.to_json()) for r in results]) + "\n")
    else:
        sys.stdout.write(_summary(task, results, ex_len, ex_method, anyangle))
    if args.plot:
        from weldplan.viz.tour import plot_tour

        title = f"{task.name}: exact optimal tour {ex_len:.1f}"
        paths = {f"{r.algorithm} ({r.smooth_length:.1f})": r.points_array for r in results}
        plot_tour(task, paths, args.plot, mesh=None if graph is None else graph.mesh, title=title)
    return 0


def _tour_settings(args: argparse.Namespace, as_printed: bool) -> TourSettings:
    """The :class:`~weldplan.planar.tour_settings.TourSettings` a run's options give."""
    from weldplan.planar.multigoal import PAPER_ITER, PAPER_POP
    from weldplan.planar.tour_settings import TourSettings

    return TourSettings(
        metric=args.metric, as_printed=as_printed, pop_size=args.pop or PAPER_POP,
        max_iter=args.iters or PAPER_ITER, two_opt=args.two_opt, polish=not args.no_polish,
        taut=not args.no_funnel, smooth=not args.no_smooth,
    )  # fmt: skip


def _algorithms(args: argparse.Namespace) -> list[str]:
    """The ``--order-by`` algorithms, checked with the other options."""
    from weldplan.optim.registry import ALGORITHMS

    if len(args.more) != 1:
        raise WeldplanError("usage: weldplan planar tour SCENARIO [options]")
    algos = [a.strip().lower() for a in args.order_by.split(",") if a.strip()]
    for a in algos:
        if a != "exact" and a not in ALGORITHMS:
            raise WeldplanError(f"unknown algorithm '{a}' (field --order-by)")
    if args.max_edge is not None and args.max_edge <= 0:
        raise WeldplanError("--max-edge must be positive")
    return algos
