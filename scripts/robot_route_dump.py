"""Dump the robot route of the car2 bench station to JSON, or compare two dumps.

The equality harness of the robot speed work: run it on two versions of the code (the same
station, the same seed) and compare the answers field by field::

    python scripts/robot_route_dump.py dump OUT/before.json -n 200 --tool torch --cache C
    python scripts/robot_route_dump.py compare OUT/before.json OUT/after.json

The dump holds what :func:`weldplan.robot.route.plan_robot_route` decides: the base, the status,
detail and branch of every weld, every row's joint vector, branch, exactness and owner, the
first check's blocked motions and bodies, and the verification's verdict. Timings are left out.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

#: the stats entries that are answers, not timings
ANSWER_STATS = (
    "placement",
    "waypoints",
    "waypoints_unsolved",
    "first_check_hits",
    "first_check_bodies",
    "collision_free",
    "hits",
    "min_manipulability",
)


def dump(n: int, tool: str, cache: Path | None, step: float, base: str | None) -> dict:
    from weldplan.bench.robot import TORCH_REACH_MM, station
    from weldplan.robot import load_robot
    from weldplan.robot.placement import BaseSearch, parse_base
    from weldplan.robot.route import plan_robot_route, tool_flange_tcp
    from weldplan.robot.settings import JointRouteSettings, RobotCell, ToolOnRobot
    from weldplan.tool.model import SHARED_GUN_DIR
    from weldplan.weld.synthetic import CAR2

    part, route, poses, gun = station(n, cache, tool)
    robot = load_robot(Path(CAR2).parents[1] / "robots/kuka_kr150r3100_2/kr150r3100_2.urdf")
    if tool == "gun":
        F = tool_flange_tcp(robot, SHARED_GUN_DIR / "spot_welding_gun.urdf", "nozzle_tip")
    else:
        F = np.eye(4)
        F[2, 3] = TORCH_REACH_MM
    kw: dict = {"base": parse_base(base)} if base else {"search": BaseSearch(step=step)}
    rr = plan_robot_route(
        route, poses, robot, tool=ToolOnRobot(F, gun), cell=RobotCell(part, **kw),
        settings=JointRouteSettings(replan=False),
    )  # fmt: skip
    return answers(rr)


def answers(rr) -> dict:
    """What a :class:`~weldplan.robot.route.RobotRoute` decides, as JSON-ready lists."""
    return {
        "base": rr.base.tolist(),
        "status": list(rr.status),
        "detail": list(rr.detail),
        "weld_branch": rr.weld_branch.tolist(),
        "weld_index": rr.weld_index.tolist(),
        "q": rr.q.tolist(),
        "branch": rr.branch.tolist(),
        "exact": rr.exact.tolist(),
        "row": rr.row.tolist(),
        "flips": list(rr.flips),
        "stats": {k: rr.stats.get(k) for k in ANSWER_STATS},
    }


def compare(a: dict, b: dict) -> list[str]:
    """The fields that differ (exact comparison: the same floats, the same words)."""
    diff = []
    for k in sorted(set(a) | set(b)):
        if k == "stats":
            for s in sorted(set(a[k]) | set(b[k])):
                if a[k].get(s) != b[k].get(s):
                    diff.append(f"stats.{s}: {a[k].get(s)!r} != {b[k].get(s)!r}")
        elif a.get(k) != b.get(k):
            diff.append(k)
    return diff


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    sub = p.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("dump")
    d.add_argument("out", type=Path)
    d.add_argument("-n", type=int, default=200)
    d.add_argument("--tool", choices=("gun", "torch"), default="torch")
    d.add_argument("--cache", type=Path, default=None)
    d.add_argument("--search-step", type=float, default=250.0)
    d.add_argument("--robot-base", default=None)
    c = sub.add_parser("compare")
    c.add_argument("a", type=Path)
    c.add_argument("b", type=Path)
    args = p.parse_args(argv)
    if args.cmd == "dump":
        out = dump(args.n, args.tool, args.cache, args.search_step, args.robot_base)
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(out))
        return 0
    diff = compare(json.loads(args.a.read_text()), json.loads(args.b.read_text()))
    for line in diff:
        sys.stdout.write(f"differs: {line}\n")
    sys.stdout.write("identical\n" if not diff else f"{len(diff)} fields differ\n")
    return 1 if diff else 0


if __name__ == "__main__":
    raise SystemExit(main())
