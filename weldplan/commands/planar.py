"""``weldplan planar SCENARIO --algorithm NAME``: plan one 2D path and measure it.

By default the pipeline of :mod:`weldplan.planar.solve` (roadmap-seeded optimiser, repair,
polish); ``--as-printed`` runs the paper's algorithm alone. The summary names the pipeline and
shows the optimiser's own path beside what each added stage changed, then the exact optimum
and the gap.

The plain form solves one scenario (a shipped name such as ``circles-1`` or a JSON file).
Further forms (``planar tour|robots|multimodal ...``) plug in through :data:`SUBCOMMANDS`:
name -> module with ``add_arguments(parser)`` (extra options, shared namespace) and
``run(args) -> int``; the first positional picks one, the others go in ``args.more``.
"""

from __future__ import annotations

import argparse
import sys
from importlib import import_module
from typing import TYPE_CHECKING

from weldplan.errors import WeldplanError

if TYPE_CHECKING:
    from weldplan.planar.solve import PlanarRun

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
    parser.add_argument(
        "--algorithm", "-a", default="lrsma", help="registered optimiser (default: lrsma)"
    )
    parser.add_argument(
        "--encoding", choices=["spline", "segments", "grid"], help="default: the scenario's"
    )
    parser.add_argument("--seed", type=int, default=None, help="random seed")
    parser.add_argument("--pop", type=int, default=None, help="population (default: paper's)")
    parser.add_argument("--iters", type=int, default=None, help="iterations (default: paper's)")
    parser.add_argument("--plot", default=None, help="write a PNG of the path here")
    parser.add_argument("--json", action="store_true", help="print the run as JSON")
    parser.add_argument(
        "--as-printed",
        action="store_true",
        help="the paper's algorithm alone, with its budget and initial population (no "
        "seeding, repair or polish)",
    )
    parser.add_argument(
        "--init",
        choices=["uniform", "problem"],
        default=None,
        help="initial population of sma/lrsma: uniform in the box (the papers; the "
        "default with --as-printed) or 'problem': a third seeded along a coarse grid path of "
        "the map (ours; the default pipeline's)",
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
    from weldplan.planar.solve import PlanarSettings, solve

    if args.algorithm.lower() not in ALGORITHMS:
        raise WeldplanError(
            f"unknown algorithm '{args.algorithm}' (field --algorithm); choose one of: "
            + (", ".join(available()) or "(none registered)")
        )
    optimizer_params = _optimizer_params(args)
    scenario = load_scenario(args.scenario)
    settings = PlanarSettings(
        encoding=args.encoding,
        pop_size=args.pop,
        max_iter=args.iters,
        optimizer_params=optimizer_params,
        as_printed=args.as_printed,
    )
    r = solve(scenario, args.algorithm, settings, rng=args.seed)
    if args.json:
        sys.stdout.write(r.to_json() + "\n")
    else:
        sys.stdout.write(summary(r))
    if args.plot:
        _plot(args.plot, scenario, r)
    return 0


def _optimizer_params(args: argparse.Namespace) -> dict | None:
    """``{"init": ...}`` when ``--init`` is given, checked against the algorithm."""
    if args.init is None:
        return None
    from weldplan.optim.registry import get_optimizer

    params = {"init": args.init}
    try:
        get_optimizer(args.algorithm, **params)
    except (TypeError, ValueError):
        raise WeldplanError(
            f"--init {args.init}: algorithm '{args.algorithm}' does not take this initial "
            "population (field --init; sma and lrsma take 'problem')"
        ) from None
    return params


def _plot(path: str, scenario: object, r: PlanarRun) -> None:
    """The run's path beside the exact optimum, as a figure at ``path``."""
    from weldplan.planar.solve import exact_optimum
    from weldplan.viz.planar import plot_paths

    # the default pipeline's path is any-angle: its optimum is the any-angle one
    ex = exact_optimum(scenario, r.encoding if r.pipeline == "as-printed" else "segments")
    what = r.algorithm if r.pipeline == "as-printed" else f"{r.algorithm}+repair+polish"
    plot_paths(
        scenario,
        {f"{what} ({r.length:.3f})": r.points},
        path,
        exact=ex.points_array,
        title=f"{scenario.name}: {what}, optimum {ex.length:.3f}",
    )


def summary(r: PlanarRun) -> str:
    """The text summary of a run: the pipeline, each stage's length, collisions and change,
    the exact optimum and the gaps (the optimiser's own and the final one)."""
    head = (
        f"scenario   {r.scenario} ({r.encoding} encoding)\n"
        f"algorithm  {r.algorithm}, {r.n_eval} evaluations, seed {r.seed}\n"
    )
    if r.pipeline == "as-printed":
        head += "pipeline   as printed: the paper's algorithm alone\n"
    else:
        head += (
            "pipeline   default: optimiser (roadmap-seeded where it takes a seeding) -> "
            "repair -> polish (--as-printed: the paper's algorithm alone)\n"
        )
    lines = [head]
    if r.stages:
        lines.append("stage      length      gap  collisions  seconds  change\n")
        prev = None
        for s in r.stages:
            gap = 100 * (s.length / r.optimum - 1.0)
            change = "" if prev is None else f"{100 * (s.length / prev - 1.0):+.2f} %"
            what = f"{change} {s.note}".strip() if prev is not None else "the optimiser's own"
            lines.append(
                f"{s.name:<9s} {s.length:8.4f} {gap:+7.2f} % {s.collisions:>10d}"
                f" {s.seconds:8.3f}  {what}\n"
            )
            prev = s.length
    kind = "any-angle" if r.pipeline == "default" or r.encoding != "grid" else "octile"
    lines.append(
        f"length     {r.length:.4f}\n"
        f"optimum    {r.optimum:.4f} (exact {kind}, {r.optimum_method or 'not computed'})\n"
        f"gap        {100 * r.gap:+.2f} %{'' if r.success else ' (of a colliding path)'}\n"
        f"smoothness {r.smoothness:.4f} rad (sum of turning angles)\n"
        f"clearance  {r.min_clearance:.4f}\n"
        f"success    {'yes' if r.success else 'no (the path collides)'}"
        f" ({r.collisions} polyline segments enter obstacles)\n"
        f"time       {r.seconds:.3f} s\n"
    )
    return "".join(lines)
