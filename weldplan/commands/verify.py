"""``weldplan verify ROUTE MESH``: re-check a saved route against the part, independently."""

from __future__ import annotations

import argparse
import sys

from weldplan.commands.demo import positive_mm
from weldplan.commands.plan import add_cell_arguments

HELP = "re-check a route JSON against the part mesh (FCL, every segment; every joint once)"


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


def run(args: argparse.Namespace) -> int:
    from weldplan.io.export import read_route
    from weldplan.io.mesh import load_part
    from weldplan.weld.verify import verify_route

    route = read_route(args.route)
    part = load_part(args.mesh, units=args.units, scale=args.scale, length=args.length)
    joints = None
    if args.joints:
        from weldplan.io.joints import read_joints

        joints = read_joints(args.joints, units=args.units)
    report = verify_route(route, part, clearance=args.clearance, joints=joints)
    if report.ok:
        print(report.describe())
        return 0
    print(f"weldplan verify: {report.describe(limit=20)}", file=sys.stderr)
    return 1
