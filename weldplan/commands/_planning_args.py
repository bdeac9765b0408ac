"""The options of a planning run (``weldplan plan`` and ``weldplan demo``) and the
:class:`~weldplan.weld.pipeline.PlanConfig` they make.

The groups are added in the order ``--help`` shows them: outputs, the planner and the sequencer,
the run (seed, workers, scale), then the tool's and the robot's options
(:mod:`weldplan.commands._tool`, :mod:`weldplan.commands._robot`).
"""

from __future__ import annotations

import argparse
from typing import Any

from weldplan.errors import WeldplanError


def add_planning_arguments(p: argparse.ArgumentParser, *, default_output: str | None) -> None:
    """Options of the planning run (outputs, planner, sequencer, seed, jobs, quiet)."""
    _add_output_arguments(p, default_output)
    _add_planner_arguments(p)
    _add_run_arguments(p)
    from weldplan.commands._robot import add_robot_arguments
    from weldplan.commands._tool import add_tool_arguments

    add_tool_arguments(p)
    add_robot_arguments(p)


def _add_output_arguments(p: argparse.ArgumentParser, default_output: str | None) -> None:
    """``-o``, ``--json``, ``--html``, ``--post``, ``--post-file``."""
    if default_output is None:
        p.add_argument("-o", "--output", required=True, help="route CSV to write")
    else:
        p.add_argument(
            "-o", "--output", default=default_output, help=f"route CSV (default {default_output})"
        )
    p.add_argument("--json", metavar="F", help="also write the whole route as JSON")
    p.add_argument("--html", metavar="F", help="also write a self-contained 3D page (meshcat)")
    p.add_argument(
        "--post",
        choices=_post_names(),
        help="also write a robot program next to the CSV (rapid: ABB .mod, krl: KUKA .src)",
    )
    p.add_argument("--post-file", metavar="F", help="where --post writes (default: CSV stem)")


def _add_planner_arguments(p: argparse.ArgumentParser) -> None:
    """The local planner, its refinement and smoothing, the sequencer."""
    p.add_argument(
        "--planner",
        default="exact",
        choices=("so-aco", "aco", "exact", "ompl"),
        help="local planner for blocked pairs (default exact: 26-connected A* + the secondary "
        "optimisation, then the refinement; so-aco: the paper's; ompl: OMPL's BIT*, 1 s a pair, on "
        "the same FCL checks; needs the ompl extra)",
    )
    p.add_argument(
        "--no-refine",
        action="store_true",
        help="skip the continuous refinement after the grid planner (with --planner so-aco: the "
        "paper's pipeline as printed; default: refine, shortcuts anywhere on the path re-checked "
        "by FCL)",
    )
    p.add_argument(
        "--smooth",
        action="store_true",
        help="give each leg a smooth path: a C2 curve between its virtual joints, checked at the "
        "clearance and exported as dense waypoints (CSV/JSON kind 'smooth'; RAPID MoveL, KRL "
        "SPLINE); a leg whose curve fails keeps its polyline and the summary says so",
    )
    p.add_argument(
        "--smooth-spacing",
        metavar="MM",
        type=positive_mm,
        default=5.0,
        help="with --smooth: largest spacing of the smooth waypoints, mm (default 5; denser "
        "where a chord would cut into the clearance)",
    )
    p.add_argument(
        "--sequencer",
        default="auto",
        choices=("auto", "fast-tsp", "pso", "exact", "nn"),
        help="joint order: auto = exact (Held-Karp) up to 13 joints, else nn (nearest neighbour "
        "+ the seeded 2-opt / Or-opt polish, reproducible); fast-tsp = a stronger engine without "
        "a seed (not reproducible); pso = the paper's TSP-PSO + polish (default auto)",
    )
    p.add_argument(
        "--aco",
        metavar="N",
        type=int,
        default=10,
        help="SO-ACO iterations N = ants M (default 10; the paper also runs 50)",
    )


def _add_run_arguments(p: argparse.ArgumentParser) -> None:
    """Seed, workers (processes, Dask), candidate pairs and memory for large stations,
    unreachable joints, quiet."""
    p.add_argument(
        "--seed", type=seed_type, default=0, help="random seed, an integer >= 0 (default 0)"
    )
    p.add_argument("--jobs", type=int, default=1, help="processes planning local paths (default 1)")
    p.add_argument(
        "--dask",
        metavar="ADDR",
        help="plan local paths on Dask: 'local' starts a LocalCluster of --jobs workers (at least "
        "2), 'tcp://HOST:PORT' joins a running scheduler (needs the 'dask' extra)",
    )
    p.add_argument(
        "--candidates",
        metavar="K",
        type=int,
        help="check and plan up front only each joint's K nearest pairs, the rest on demand "
        "(for hundreds of joints; default: every pair checked straight)",
    )
    p.add_argument(
        "--candidate-radius",
        metavar="MM",
        type=float,
        help="with --candidates: neighbours farther than this are planned only on demand",
    )
    p.add_argument(
        "--memory-limit",
        metavar="GB",
        type=positive_gb,
        help="refuse up front a run whose estimated peak memory (grid + pair tables) exceeds "
        "this (default: 80 %% of the memory available at start)",
    )
    p.add_argument(
        "--skip-unreachable",
        action="store_true",
        help="plan the largest group of joints that reach each other and list the others, with "
        "the reason, in the summary and the route JSON (stats.skipped); exit code 3",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bars and no summary on stdout")


def positive_mm(text: str) -> float:
    """argparse type: a positive, finite number of millimetres."""
    return _positive(text, "mm")


def _positive(text: str, unit: str) -> float:
    """``float(text)`` when it is a positive, finite number, else an argparse error naming
    ``unit``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0 < value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number of {unit}, got {text!r}")
    return value


def seed_type(text: str) -> int:
    """argparse type: an integer >= 0 (what numpy's ``default_rng`` takes)."""
    from weldplan.errors import ConfigError
    from weldplan.weld.validate import seed

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    try:
        return seed(value)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(exc.message) from None


def positive_gb(text: str) -> float:
    """argparse type: a positive, finite number of GB."""
    return _positive(text, "GB")


def _post_names() -> list[str]:
    from weldplan.io.export import POSTS

    return sorted(POSTS)


def config_from_args(args: argparse.Namespace) -> Any:
    from weldplan.weld.pipeline import PlanConfig

    if args.aco < 1:
        raise WeldplanError(f"--aco must be >= 1, got {args.aco}")
    if args.jobs < 1:
        raise WeldplanError(f"--jobs must be >= 1, got {args.jobs}")
    return PlanConfig(
        clearance=getattr(args, "clearance", 5.0),
        pitch=getattr(args, "pitch", 5.0),
        margin=getattr(args, "margin", 150.0),
        planner=args.planner,
        sequencer=args.sequencer,
        aco={"n_iterations": args.aco, "n_ants": args.aco},
        refine=not getattr(args, "no_refine", False),
        smooth=bool(getattr(args, "smooth", False)),
        smooth_spacing=getattr(args, "smooth_spacing", 5.0),
        candidates=getattr(args, "candidates", None),
        candidate_radius=getattr(args, "candidate_radius", None),
        skip_unreachable=bool(getattr(args, "skip_unreachable", False)),
        memory_limit=getattr(args, "memory_limit", None),
    )
