"""``weldplan plan MESH JOINTS -o route.csv``: the ordered, verified, collision-free route."""

from __future__ import annotations

import argparse

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
    p.add_argument("mesh", help="part mesh (STL, OBJ, PLY, OFF, GLB/GLTF)")
    p.add_argument("joints", help="weld joints CSV (id, x, y, z[, dx, dy, dz])")
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
    add_part_pose_arguments(p)
    add_planning_arguments(p, default_output=None)


def run(args: argparse.Namespace) -> int:
    from weldplan.weld.pipeline import PlanConfig

    # validates clearance, pitch and margin before the (slow) cell is built
    PlanConfig(clearance=args.clearance, pitch=args.pitch, margin=args.margin)
    if not 0.0 < args.approach_cone <= 90.0:
        from weldplan.errors import WeldplanError

        raise WeldplanError(
            f"--approach-cone must lie in (0, 90] degrees, got {args.approach_cone}"
        )
    pose = part_pose_from_args(args)  # its floor: --floor-z, default 0 in the cell
    if pose is not None:  # a robot stands on the cell's floor and is checked against it
        args.floor_z = pose.floor_z if args.robot else None

    def make_cell():
        from weldplan.weld.cell import load_cell

        return load_cell(
            args.mesh,
            args.joints,
            units=args.units,
            scale=args.scale,
            length=args.length,
            pitch=args.pitch,
            clearance=args.clearance,
            margin=args.margin,
            approach_cone=args.approach_cone,
            max_joint_distance=args.max_joint_distance,
            part_pose=pose,
        )

    def joint_points():
        import logging

        from weldplan.io.joints import read_joints

        # read again by load_cell: its warnings (ignored columns, ...) are said there, once
        logger = logging.getLogger("weldplan.io.joints")
        level = logger.level
        logger.setLevel(logging.ERROR)
        try:
            xyz = read_joints(args.joints, units=args.units).xyz
            return xyz if pose is None else pose.to_cell(xyz)  # the grid's box, less the lift
        finally:
            logger.setLevel(level)

    return run_planning(
        args,
        make_cell,
        title=f"weldplan plan {args.mesh} {args.joints}",
        joint_points=joint_points,
    )
