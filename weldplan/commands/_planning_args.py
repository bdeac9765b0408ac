"""The options of a planning run (``weldplan plan`` and ``weldplan demo``) and the
:class:`~weldplan.weld.pipeline.PlanConfig` they make.

The groups are added in the order ``--help`` shows them: outputs, the planner and the sequencer,
the run (seed, workers, scale), then the tool's and the robot's options
(:mod:`weldplan.commands._tool`, :mod:`weldplan.commands._robot`).
"""

from __future__ import annotations

import argparse
import math
from typing import Any


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
        p.add_argument(
            "-o", "--output", help="route CSV to write (required, but for a station file's own)"
        )
    else:
        p.add_argument(
            "-o", "--output", default=default_output, help=f"route CSV (default {default_output})"
        )
    p.add_argument("--json", metavar="F", help="also write the whole route as JSON")
    p.add_argument("--html", metavar="F", help="also write a self-contained 3D page (meshcat)")
    p.add_argument("--png", metavar="F", help="also write a picture of the cell (needs Chromium)")
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
    _add_sequencer_arguments(p)


def _add_sequencer_arguments(p: argparse.ArgumentParser) -> None:
    """``--sequencer`` and ``--aco``."""
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
        "--seed",
        type=seed_type,
        help="random seed, an integer >= 0 (default 0, or the station file's seed)",
    )
    p.add_argument(
        "--jobs", type=int, help="processes planning local paths (default 1, or the station's)"
    )
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


def add_part_pose_arguments(p: argparse.ArgumentParser) -> None:
    """``--up``, ``--part-pose``, ``--fixture-z``: the part's pose in the cell
    (:mod:`weldplan.cellframe`), for ``plan`` and ``verify``."""
    g = p.add_argument_group(
        "the part in the cell (everything is then planned and written in the cell frame: z up, "
        "the floor at --floor-z, default 0; the programs' work object / BASE carry the pose)"
    )
    g.add_argument(
        "--up",
        metavar="AXIS",
        help="the part's axis that points up in the cell: x, y, z, -x, -y or -z (y: (x, y, z) -> "
        "(x, -z, y), a quarter turn about x); the part then stands on the floor (--fixture-z 0)",
    )
    g.add_argument(
        "--part-pose",
        metavar="X,Y,Z,RX,RY,RZ|FILE",
        help="the part frame in the cell: mm and degrees, R = Rz(rz) Ry(ry) Rx(rx) (fixed axes "
        "x then y then z; KUKA A,B,C = rz,ry,rx), or a text file of a 4x4 matrix (mm)",
    )
    g.add_argument(
        "--fixture-z",
        metavar="MM",
        help="height of the part's lowest point above the floor, mm (replaces the pose's z; "
        "default 0 with --up, the pose's own z with --part-pose)",
    )


def part_pose_from_args(args: argparse.Namespace) -> Any:
    """The :class:`~weldplan.cellframe.PartPose` the options give (not yet placed on the
    part), ``None`` without ``--up`` / ``--part-pose``; a one-line InputError naming the
    option for a bad axis, NaN, a non-rotation matrix or a bad combination."""
    from weldplan.cellframe import PartPose, parse_part_pose
    from weldplan.errors import InputError

    up, pose, fixture = (getattr(args, k, None) for k in ("up", "part_pose", "fixture_z"))
    if up is None and pose is None:
        if fixture is not None:
            raise InputError("needs --up or --part-pose", field="--fixture-z")
        return None
    if up is not None and pose is not None:
        raise InputError("give --up or --part-pose, not both", field="--part-pose")
    fix = None
    if fixture is not None:
        try:
            fix = float(fixture)
        except ValueError:
            fix = math.nan
        if not math.isfinite(fix):
            raise InputError(f"must be a finite number of mm, got {fixture!r}", field="--fixture-z")
    floor = getattr(args, "floor_z", None)
    floor = 0.0 if floor is None else float(floor)
    if up is not None:
        try:
            return PartPose.from_up(up, fixture_z=0.0 if fix is None else fix, floor_z=floor)
        except InputError as exc:
            raise InputError(exc.message, field="--up") from None
    return parse_part_pose(pose, fixture_z=fix, floor_z=floor)


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
    """The :class:`~weldplan.weld.pipeline.PlanConfig` of the options."""
    from weldplan.commands._station_args import route_settings

    return route_settings(args).config(
        getattr(args, "clearance", 5.0), getattr(args, "pitch", 5.0), getattr(args, "margin", 150.0)
    )
