"""The options of a planning run (``weldplan plan`` and ``weldplan demo``) and the
:class:`~weldplan.weld.pipeline.PlanConfig` they make.

``--help`` shows one group per stage, in the order the stages run: the outputs, the cell, the
point-tip route, the run (seed, workers), the tool, the tool stage, the robot, the robot stage.
A stage's options are its settings object's fields (:mod:`weldplan.commands._settings_args`):
their defaults and help are the fields', and each option's help names the station file's key.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterable
from typing import Any

from weldplan.commands._settings_args import add_settings_options
from weldplan.commands._types import positive_gb, positive_mm, seed_type
from weldplan.station.model import CellSettings, RouteSettings, Station

#: what the commands import from here
__all__ = [
    "add_cell_stage_arguments", "add_part_pose_arguments", "add_planning_arguments",
    "config_from_args", "part_pose_from_args", "positive_gb", "positive_mm", "seed_type",
]  # fmt: skip


def add_planning_arguments(p: argparse.ArgumentParser, *, default_output: str | None) -> None:
    """The outputs, the route stage, the run, the tool and the robot (each a help group); the
    cell stage is :func:`add_cell_stage_arguments`, added first by the command."""
    _add_output_arguments(p, default_output)
    g = p.add_argument_group(
        "route stage: the point-tip route's local paths and weld order (station file: [route])"
    )
    add_settings_options(g, RouteSettings, "[route]")
    _add_run_arguments(p)
    from weldplan.commands._robot import add_robot_arguments
    from weldplan.commands._tool import add_tool_arguments

    add_tool_arguments(p)
    add_robot_arguments(p)


def add_cell_stage_arguments(p: argparse.ArgumentParser, only: Iterable[str] | None = None) -> None:
    """The cell stage's options: the station's ``--clearance`` and :class:`CellSettings`' fields
    (``only``: these fields)."""
    g = p.add_argument_group(
        "cell stage: the search grid about the welds and their virtual joints (station file: "
        "clearance, [cell])"
    )
    add_settings_options(g, Station, "", only=["clearance"])
    add_settings_options(g, CellSettings, "[cell]", only=only)


def _add_output_arguments(p: argparse.ArgumentParser, default_output: str | None) -> None:
    """The files a run writes (station file: ``[output]``)."""
    g = p.add_argument_group("outputs (station file: [output]; written only when all is verified)")
    if default_output is None:
        help_o = "route CSV to write (required, but for a station file's own)"
    else:
        help_o = f"route CSV (default {default_output})"
    g.add_argument("-o", "--output", default=default_output, help=help_o)
    g.add_argument("--json", metavar="F", help="also write the whole route as JSON")
    g.add_argument("--html", metavar="F", help="also write a self-contained 3D page (meshcat)")
    g.add_argument("--png", metavar="F", help="also write a picture of the cell (needs Chromium)")
    g.add_argument(
        "--post",
        choices=_post_names(),
        help="also write a robot program next to the CSV (rapid: ABB .mod, krl: KUKA .src)",
    )
    g.add_argument("--post-file", metavar="F", help="where --post writes (default: CSV stem)")
    g.add_argument(
        "--tool-csv",
        metavar="F",
        help="with --tool: also write the tool's verified path as CSV (the transitions in "
        "the tool's order, one row per TCP pose with its quaternion: the motion the swept "
        "check proved free; weldplan.io.tool_csv)",
    )
    g.add_argument(
        "--trajectory", metavar="F", help="with --robot: write the timed joint trajectory as CSV"
    )
    g.add_argument(
        "--robot-html",
        metavar="F",
        help="with --robot: write a 3D page of the robot, tool and part animated along the "
        "timed trajectory",
    )


def _add_run_arguments(p: argparse.ArgumentParser) -> None:
    """Seed, workers (processes, Dask), quiet: how the run goes, not the station's."""
    g = p.add_argument_group("run: seed, workers, progress (beside a station file too)")
    g.add_argument(
        "--seed",
        type=seed_type,
        help="random seed, an integer >= 0 (default 0, or the station file's seed)",
    )
    g.add_argument(
        "--jobs",
        type=int,
        help="processes planning local paths, or a station's robots side by side (default 1, "
        "or the station's)",
    )
    g.add_argument(
        "--dask",
        metavar="ADDR",
        help="plan local paths (a station's robots) on Dask: 'local' starts a LocalCluster of "
        "--jobs workers (at least 2), 'tcp://HOST:PORT' joins a running scheduler (needs the "
        "'dask' extra)",
    )
    g.add_argument("--quiet", action="store_true", help="no progress bars and no summary on stdout")


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


def _post_names() -> list[str]:
    from weldplan.io.export import POSTS

    return sorted(POSTS)


def config_from_args(args: argparse.Namespace) -> Any:
    """The :class:`~weldplan.weld.pipeline.PlanConfig` of the options."""
    from weldplan.commands._station_args import route_settings

    return route_settings(args).config(
        getattr(args, "clearance", 5.0), getattr(args, "pitch", 5.0), getattr(args, "margin", 150.0)
    )
