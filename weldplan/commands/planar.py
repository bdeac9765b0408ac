"""``weldplan planar SCENARIO --algorithm NAME``: plan one 2D path and measure it.

The plain form solves one scenario (a shipped name such as ``circles-1`` or a JSON file).
Further forms (``planar tour|robots|multimodal ...``) plug in through :data:`SUBCOMMANDS`:
name -> module with ``add_arguments(parser)`` (extra options, shared namespace) and
``run(args) -> int``; the first positional picks one, the others go in ``args.more``.
"""

from __future__ import annotations

import argparse
import sys
from importlib import import_module

from weldplan.errors import WeldplanError

HELP = "plan a 2D path on a scenario with one optimiser (length, gap to optimum, time)"

#: planar sub-forms: name -> module (added by later work; the plain form needs none)
SUBCOMMANDS: dict[str, str] = {
    "tour": "weldplan.commands.planar_tour",
    "robots": "weldplan.commands.planar_robots",
    "multimodal": "weldplan.commands.planar_multimodal",
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "scenario",
        help="scenario name (see assets/scenarios) or JSON file"
        + (f"; or one of: {', '.join(SUBCOMMANDS)}" if SUBCOMMANDS else ""),
    )
    parser.add_argument("more", nargs="*", help=argparse.SUPPRESS)
    parser.add_argument("--algorithm", "-a", default="lrsma", help="registered optimiser")
    parser.add_argument(
        "--encoding", choices=["spline", "segments", "grid"], help="default: the scenario's"
    )
    parser.add_argument("--seed", type=int, default=None, help="random seed")
    parser.add_argument("--pop", type=int, default=None, help="population (default: paper's)")
    parser.add_argument("--iters", type=int, default=None, help="iterations (default: paper's)")
    parser.add_argument("--plot", default=None, help="write a PNG of the path here")
    parser.add_argument("--json", action="store_true", help="print the run as JSON")
    parser.add_argument(
        "--init",
        choices=["uniform", "problem"],
        default="uniform",
        help="initial population of sma/lrsma: uniform in the box (the papers) or 'problem': "
        "a third seeded along a coarse grid path of the map (ours, off by default)",
    )
    for module_name in SUBCOMMANDS.values():
        import_module(module_name).add_arguments(parser)


def run(args: argparse.Namespace) -> int:
    if args.scenario in SUBCOMMANDS:
        return int(import_module(SUBCOMMANDS[args.scenario]).run(args) or 0)
    if args.more:
        raise WeldplanError(f"unexpected arguments: {' '.join(args.more)}")
    from weldplan.optim.registry import ALGORITHMS, available
    from weldplan.planar.scenarios import load_scenario
    from weldplan.planar.solve import exact_optimum, solve

    if args.algorithm.lower() not in ALGORITHMS:
        raise WeldplanError(
            f"unknown algorithm '{args.algorithm}' (field --algorithm); choose one of: "
            + (", ".join(available()) or "(none registered)")
        )
    optimizer_params = None
    if args.init != "uniform":
        from weldplan.optim.registry import get_optimizer

        optimizer_params = {"init": args.init}
        try:
            get_optimizer(args.algorithm, **optimizer_params)
        except (TypeError, ValueError):
            raise WeldplanError(
                f"--init {args.init}: algorithm '{args.algorithm}' does not take this initial "
                "population (field --init; sma and lrsma take 'problem')"
            ) from None
    scenario = load_scenario(args.scenario)
    r = solve(
        scenario,
        args.algorithm,
        encoding=args.encoding,
        pop_size=args.pop,
        max_iter=args.iters,
        rng=args.seed,
        optimizer_params=optimizer_params,
    )
    if args.json:
        sys.stdout.write(r.to_json() + "\n")
    else:
        sys.stdout.write(
            f"scenario   {r.scenario} ({r.encoding} encoding)\n"
            f"algorithm  {r.algorithm}, {r.n_eval} evaluations, seed {r.seed}\n"
            f"length     {r.length:.4f}\n"
            f"optimum    {r.optimum:.4f} (exact)\n"
            f"gap        {100 * r.gap:+.2f} %{'' if r.success else ' (of a colliding path)'}\n"
            f"smoothness {r.smoothness:.4f} rad (sum of turning angles)\n"
            f"clearance  {r.min_clearance:.4f}\n"
            f"success    {'yes' if r.success else 'no (the path collides)'}"
            f" ({r.collisions} polyline segments touch obstacles)\n"
            f"time       {r.seconds:.3f} s\n"
        )
    if args.plot:
        from weldplan.viz.planar import plot_paths

        ex = exact_optimum(scenario, r.encoding)
        plot_paths(
            scenario,
            {f"{r.algorithm} ({r.length:.3f})": r.points},
            args.plot,
            exact=ex.points_array,
            title=f"{scenario.name}: {r.algorithm}, optimum {ex.length:.3f}",
        )
    return 0
