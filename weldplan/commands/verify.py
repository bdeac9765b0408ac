"""``weldplan verify ROUTE MESH``: re-check a saved route against the part, independently.

A thin call on the library: :func:`weldplan.station.saved.load_plan` reads the route and places
the part, :meth:`~weldplan.station.saved.SavedPlan.verify` runs the re-checks
(:mod:`weldplan.station.recheck`), and this command prints each check's line and exits with the
verdict's code.
"""

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
    p.add_argument(
        "route",
        help="route JSON written by `weldplan plan --json`, or the station JSON of a station "
        "of several robots (route_station.json)",
    )
    p.add_argument(
        "mesh", nargs="?", help="the part mesh the route was planned for (not with a station JSON)"
    )
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
    p.add_argument(
        "--station",
        metavar="TOML",
        help="with a station JSON: the station file (default: the one the plan records)",
    )


def run(args: argparse.Namespace) -> int:
    """Load the route with the part (:func:`weldplan.station.saved.load_plan`), re-check it
    (:meth:`~weldplan.station.saved.SavedPlan.verify`) and print each check's line: exit 0 ok,
    1 a check failed, 3 ok but welds left out (2, bad input, is the CLI's)."""
    from weldplan.commands._tool import tool_from_args
    from weldplan.multi.saved import is_station_json
    from weldplan.station.recheck import RobotFiles
    from weldplan.station.saved import PartFiles, load_plan

    if args.mesh is None or is_station_json(args.route):
        return _verify_station(args)

    files = PartFiles(
        units=args.units, scale=args.scale, length=args.length, joints=args.joints,
        part_pose=part_pose_from_args(args),
    )  # fmt: skip
    saved = load_plan(args.route, mesh=args.mesh, part=files)
    tool = tool_from_args(args)  # a bad --tool fails before any check
    verdict = saved.verify(
        tool=tool, robot=RobotFiles(args.robot, args.opw), clearance=args.clearance
    )
    return _say(verdict)


def _verify_station(args: argparse.Namespace) -> int:
    """A station JSON: every check of :meth:`weldplan.multi.saved.SavedStationPlan.verify`, one
    line each (a failure on stderr); the verdict's exit code."""
    from weldplan.errors import WeldplanError
    from weldplan.multi.saved import load_station_plan

    if args.mesh is not None:
        raise WeldplanError(f"{args.route} is a station JSON: give no mesh (its station names it)")
    saved = load_station_plan(args.route)
    station = None
    if args.station is not None:
        from weldplan.station.load import load_station

        station = load_station(args.station)
    verdict = saved.verify(station=station)
    for c in verdict.checks:
        line = f"{c.name} {'ok' if c.ok else 'FAILED'}: {c.text}"
        print(line, file=sys.stdout if c.ok else sys.stderr)
    if verdict.partial:
        for line in _partial_lines(verdict):
            print(f"weldplan verify: ok, {line}", file=sys.stderr)
    return int(verdict.exit_code)


def _partial_lines(verdict: object) -> list[str]:
    """Why a station's verdict is partial, one line a cause: the welds left out (unreached,
    or left out by a robot's plan), the transitions a robot's plan left out (``a->b``), and
    the robots the replay found too close (the two robots, where each was, the distance
    against the clearance), never called welds."""
    left, close = [], []
    for c in verdict.checks:  # type: ignore[attr-defined]
        (close if c.name == "interference" else left).extend(c.left_out)
    welds = [x for x in left if "->" not in x]
    legs = [x for x in left if "->" in x]
    out = [f"welds left out: {', '.join(welds)}"] if welds else []
    out += [f"transitions left out: {', '.join(legs)}"] if legs else []
    return out + [f"robots too close by the replay: {x}" for x in close]


def _say(verdict: object) -> int:
    """Print the verdict's checks (stdout), its failure (stderr, one line); its exit code."""
    for c in verdict.checks:  # type: ignore[attr-defined]
        if c.name == "part pose":
            continue
        if not c.ok:
            what = "" if c.name == "route" else f"{c.name}: "
            print(f"weldplan verify: {what}{c.text}", file=sys.stderr)
            break
        print(c.text if c.name == "route" else f"{c.name} ok: {c.text}")
    if ("tool poses", "no tool given") in verdict.not_run:  # type: ignore[attr-defined]
        print("the route carries tool poses: pass --tool to re-check them")
    return int(verdict.exit_code)  # type: ignore[attr-defined]
