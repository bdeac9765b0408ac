"""``weldplan plan MESH JOINTS -o route.csv`` or ``weldplan plan station.toml``: the ordered,
verified, collision-free route (and, with a tool and a robot, their poses, paths and program).

The quick form's options map onto a :class:`~weldplan.station.model.Station`
(:mod:`weldplan.commands._station_args`); a station file is read by
:func:`weldplan.station.load_station` (docs/station.md). Both run :func:`weldplan.plan`."""

from __future__ import annotations

import argparse
import dataclasses

from weldplan.commands._planning import add_planning_arguments, run_planning
from weldplan.commands._planning_args import (
    add_cell_stage_arguments,
    add_part_pose_arguments,
    part_pose_from_args,
)

HELP = "plan the ordered collision-free torch route through the weld joints of a part"


def add_cell_arguments(p: argparse.ArgumentParser) -> None:
    """Options for loading a part (shared by plan, verify and view; station file: [part])."""
    g = p.add_argument_group("part: how its files are read (station file: [part])")
    g.add_argument(
        "--units", default="mm", choices=("mm", "m"), help="units of the mesh and joints files"
    )
    g.add_argument("--scale", type=float, help="extra scale factor applied to the mesh")
    g.add_argument(
        "--length", type=float, help="scale the mesh so its longest side is this many mm"
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "mesh", help="part mesh (STL, OBJ, PLY, OFF, GLB/GLTF), or a station file (.toml)"
    )
    p.add_argument("joints", nargs="?", help="weld joints CSV (id, x, y, z[, dx, dy, dz])")
    add_cell_arguments(p)
    add_part_pose_arguments(p)
    add_cell_stage_arguments(p)
    add_planning_arguments(p, default_output=None)
    from weldplan.commands._station_args import record_defaults

    record_defaults(p)
    p.set_defaults(usage_error=p.error)  # -o is required in the quick form only


def run(args: argparse.Namespace) -> int:
    from weldplan.commands import _station_args
    from weldplan.errors import WeldplanError
    from weldplan.station.model import PartSpec

    if args.joints is None:
        if not args.mesh.lower().endswith(".toml"):
            raise WeldplanError("give MESH JOINTS, or a station file (.toml)")
        station = _station_args.station_from_file(args, args.mesh)
        title = f"weldplan plan {args.mesh}"
        if len(station.robots) > 1:  # several robots: a station plan and its files
            from weldplan.commands._station_plan import run_station

            return run_station(args, station, title=title)
    else:
        if args.output is None:
            args.usage_error("the following arguments are required: -o/--output")
        part = PartSpec(args.mesh, args.joints, args.units, args.scale, args.length)
        pose = part_pose_from_args(args)  # its floor: --floor-z, default 0 in the cell
        if pose is not None:  # a robot stands on the cell's floor and is checked against it
            args.floor_z = pose.floor_z if args.robot else None
        station = dataclasses.replace(_station_args.station_from_args(args, part), part_pose=pose)
        title = f"weldplan plan {args.mesh} {args.joints}"
    return run_planning(args, station, title=title)
