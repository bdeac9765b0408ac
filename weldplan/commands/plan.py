"""``weldplan plan MESH JOINTS -o route.csv`` or ``weldplan plan station.toml``: the ordered,
verified, collision-free route (and, with a tool and a robot, their poses, paths and program).

The quick form's options map onto a :class:`~weldplan.station.model.Station`
(:mod:`weldplan.commands._station_args`); a station file is read by
:func:`weldplan.station.load_station` (docs/station.md). Both run :func:`weldplan.plan`."""

from __future__ import annotations

import argparse
import dataclasses

from weldplan.commands._planning import add_planning_arguments, run_planning
from weldplan.commands._planning_args import add_part_pose_arguments, part_pose_from_args
from weldplan.commands.demo import positive_mm

HELP = "plan the ordered collision-free torch route through the weld joints of a part"


def add_cell_arguments(p: argparse.ArgumentParser) -> None:
    """Options for loading a part (shared by plan, verify and view)."""
    p.add_argument(
        "--units", default="mm", choices=("mm", "m"), help="units of the mesh and joints files"
    )
    p.add_argument("--scale", type=float, help="extra scale factor applied to the mesh")
    p.add_argument(
        "--length", type=float, help="scale the mesh so its longest side is this many mm"
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "mesh", help="part mesh (STL, OBJ, PLY, OFF, GLB/GLTF), or a station file (.toml)"
    )
    p.add_argument("joints", nargs="?", help="weld joints CSV (id, x, y, z[, dx, dy, dz])")
    add_cell_arguments(p)
    p.add_argument("--clearance", type=positive_mm, default=5.0, help="torch-tip radius, mm (5)")
    p.add_argument(
        "--pitch", type=positive_mm, default=5.0, help="voxel size of the search grid, mm (5)"
    )
    p.add_argument(
        "--margin", type=positive_mm, default=150.0, help="grid margin around joints, mm (150)"
    )
    p.add_argument(
        "--approach-cone",
        type=float,
        default=45.0,
        help="degrees: each virtual joint lies within this angle of its joint's approach "
        "direction (45; 90 = anywhere on the torch side)",
    )
    p.add_argument(
        "--max-joint-distance",
        type=positive_mm,
        metavar="MM",
        help="largest distance from a joint to the part's surface, mm (default: the larger of "
        "20 and 4 x (clearance + pitch), 40 at the defaults); a joint farther is an error",
    )
    p.add_argument(
        "--spot-depth",
        type=float,
        default=0.0,
        metavar="MM",
        help="mm below the surface, along the approach, that the weld spots lie (a spot on the "
        "faying surface of a sheet stack: the near sheet's gauge plus the gap); the approach "
        "cone starts that far out (0: spots on the surface)",
    )
    add_part_pose_arguments(p)
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
    else:
        if args.output is None:
            args.usage_error("the following arguments are required: -o/--output")
        if not 0.0 < args.approach_cone <= 90.0:
            raise WeldplanError(
                f"--approach-cone must lie in (0, 90] degrees, got {args.approach_cone}"
            )
        part = PartSpec(args.mesh, args.joints, args.units, args.scale, args.length)
        pose = part_pose_from_args(args)  # its floor: --floor-z, default 0 in the cell
        if pose is not None:  # a robot stands on the cell's floor and is checked against it
            args.floor_z = pose.floor_z if args.robot else None
        station = dataclasses.replace(
            _station_args.station_from_args(args, part), part_pose=pose
        )
        title = f"weldplan plan {args.mesh} {args.joints}"
    return run_planning(args, station, title=title)
