"""``weldplan verify ROUTE MESH``: re-check a saved route against the part, independently."""

from __future__ import annotations

import argparse
import sys

from weldplan.commands._planning_args import add_part_pose_arguments, part_pose_from_args
from weldplan.commands.demo import positive_mm
from weldplan.commands.plan import add_cell_arguments

HELP = (
    "re-check a route JSON against the part mesh (FCL, every segment; every joint once; with "
    "--tool the weld poses and the transitions of the whole tool)"
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("route", help="route JSON written by `weldplan plan --json`")
    p.add_argument("mesh", help="the part mesh the route was planned for")
    add_cell_arguments(p)
    p.add_argument(
        "--clearance",
        type=positive_mm,
        help="torch-tip radius, mm (default: the route's own; a route that records its "
        "provenance is refused at another)",
    )
    p.add_argument("--joints", help="joints CSV: the route must visit exactly these joints")
    add_part_pose_arguments(p)
    from weldplan.commands._tool import add_tool_arguments

    add_tool_arguments(p, search=False)
    p.add_argument(
        "--robot",
        metavar="URDF",
        help="the robot of a route that carries a robot route (default: the URDF it names)",
    )
    p.add_argument("--opw", metavar="F", help="OPW parameters (default: beside the URDF)")


def run(args: argparse.Namespace) -> int:
    from weldplan.cellframe import recorded_pose
    from weldplan.commands._tool import tool_from_args
    from weldplan.io.export import read_route
    from weldplan.io.mesh import load_part
    from weldplan.tool.check_route import check_tool_provenance, verify_route_poses
    from weldplan.weld.verify import verify_route

    given = part_pose_from_args(args)
    route = read_route(args.route)
    part = load_part(args.mesh, units=args.units, scale=args.scale, length=args.length)
    pose = recorded_pose(route.provenance, given, part, path=args.route)
    joints = None
    if args.joints:
        from weldplan.io.joints import read_joints

        joints = read_joints(args.joints, units=args.units)
    if pose is not None:  # re-applied from the route: the checks run in its cell frame
        part = pose.mesh_to_cell(part)
        if joints is not None:
            joints = pose.joints_to_cell(joints)
    tool = tool_from_args(args)  # a bad --tool fails before any check
    if tool is not None:
        check_tool_provenance(route, tool[1], args.route)
    report = verify_route(route, part, clearance=args.clearance, joints=joints)
    if not report.ok:
        print(f"weldplan verify: {report.describe(limit=20)}", file=sys.stderr)
        return 1
    print(report.describe())
    if tool is None:
        if route.tool:
            print("the route carries tool poses: pass --tool to re-check them")
        return 0
    check = verify_route_poses(route, part, tool[0])
    if not check.ok:
        print(f"weldplan verify: tool poses: {check.describe()}", file=sys.stderr)
        return 1
    print(f"tool poses ok: {check.describe()}")
    from weldplan.tool.check_route import verify_route_sweeps

    sweeps = verify_route_sweeps(route, part, tool[0])
    if sweeps is not None and not sweeps.ok:
        print(f"weldplan verify: tool transitions: {sweeps.describe()}", file=sys.stderr)
        return 1
    if sweeps is not None:
        print(f"tool transitions ok: {sweeps.describe()}")
    robot = _verify_robot(args, route, part, tool[0])
    if robot is None:
        return 1
    if check.missing or (sweeps is not None and sweeps.blocked) or robot:
        from weldplan.errors import EXIT_PARTIAL

        return EXIT_PARTIAL
    return 0


def _verify_robot(
    args: argparse.Namespace, route: object, part: object, tool: object
) -> tuple[str, ...] | None:
    """Re-check the robot route the route carries, if any (:mod:`weldplan.robot.routejson`):
    FK, joint limits, robot + tool collision. ``None`` (said on stderr) when it fails, else the
    welds its program leaves out (a partial route: exit 3)."""
    from weldplan.robot.routejson import robot_route_of, verify_robot_route

    rr = robot_route_of(route, args.route)
    if rr is None:
        return ()
    urdf = args.robot or route.tool["robot"].get("urdf")  # type: ignore[attr-defined]
    from weldplan.robot import load_robot

    robot = load_robot(urdf, args.opw)
    check = verify_robot_route(route, rr, robot, part, tool)
    if not check.ok:
        print(f"weldplan verify: robot route: {check.describe()}", file=sys.stderr)
        return None
    print(f"robot route ok: {check.describe()}")
    return check.left_out
