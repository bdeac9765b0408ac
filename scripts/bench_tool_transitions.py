"""Benchmark: the swept gun's transitions on the demo cell and the car2 synthetic stations.

Usage (from the repository root; car2 is scaled to 4500 mm as in docs/bench-scale.md)::

    python scripts/bench_tool_transitions.py [--stations demo,car2_50] [--se3-time 5]
        [--orders tool,route] [--json DIR]

For each station: the point-tip route, the gun poses along it, then for each order (``tool``:
:func:`weldplan.tool.tool_order.tool_order`; ``route``: the point-tip order) the transitions
(:func:`weldplan.tool.transitions.plan_transitions`) and their independent re-check
(:func:`weldplan.tool.verify_sweeps.verify_sweeps`). Prints a markdown table: welds reached /
total, transitions free / total, re-planned in SE(3), TCP path length and orientation change of
the tool path, the point-tip route's length, seconds, the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import weldplan
from weldplan.tool import plan_weld_poses, shared_spot_gun
from weldplan.tool.tool_order import DEFAULT_ROT_WEIGHT, tool_order
from weldplan.tool.transitions import DEFAULT_RETRACT, DEFAULT_SIDE_EXIT, plan_transitions
from weldplan.tool.verify_sweeps import verify_sweeps

ROOT = Path(__file__).resolve().parents[1]
CAR2 = ROOT.parent / "shared" / "data" / "bodies" / "car2.obj"


def _cell(name: str):
    if name == "demo":
        return weldplan.demo_cell()
    joints = ROOT / "assets" / "car2" / f"car2_synthetic_{name.split('_')[1]}.csv"
    return weldplan.load_cell(CAR2, joints, length=4500)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stations", default="demo,car2_50")
    ap.add_argument("--orders", default="tool,route")
    ap.add_argument("--se3-time", type=float, default=5.0)
    ap.add_argument("--retract", type=float, default=DEFAULT_RETRACT)
    ap.add_argument("--side-exit", type=float, default=DEFAULT_SIDE_EXIT)
    ap.add_argument("--rot-weight", type=float, default=DEFAULT_ROT_WEIGHT)
    ap.add_argument("--json", help="folder to write each tool path's JSON to")
    args = ap.parse_args()
    gun = shared_spot_gun()
    print(f"{platform.node()} ({os.cpu_count()} CPUs), load average {os.getloadavg()}")
    print(
        f"retract {args.retract:g} mm, side exit {args.side_exit:g} mm, rot weight "
        f"{args.rot_weight:g} mm/rad, SE(3) {args.se3_time:g} s a transition\n"
    )
    print(
        "| station | order | welds ok / total | transitions free / total | SE(3) re-planned "
        "| tool path mm | rotation deg | point-tip route mm | re-check | s (poses, transitions, "
        "re-check) | load |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in args.stations.split(","):
        cell = _cell(name)
        route = weldplan.plan_route(cell, rng=0)
        t0 = time.perf_counter()
        poses = plan_weld_poses(cell, route, gun)
        t_poses = time.perf_counter() - t0
        for order_name in args.orders.split(","):
            order, stats = tool_order(poses, args.retract, args.rot_weight, rng=0)
            if order_name == "route":
                order = [p.id for p in poses.poses if p.ok]
            t1 = time.perf_counter()
            path = plan_transitions(
                cell.part, gun, poses, order=order, retract=args.retract,
                se3=args.se3_time > 0, time_s=max(args.se3_time, 1e-3), seed=0,
                rot_weight=max(args.rot_weight, 1.0), side_exit=args.side_exit, stats=stats,
            )  # fmt: skip
            t_tr = time.perf_counter() - t1
            t2 = time.perf_counter()
            v = verify_sweeps(path, poses, cell.part, gun)
            t_v = time.perf_counter() - t2
            n = len(path.transitions)
            print(
                f"| {name} | {order_name} | {poses.n_ok} / {len(poses.poses)} "
                f"| {n - len(path.blocked)} / {n} | {path.n_replanned} | {path.length:.1f} "
                f"| {path.rotation:.1f} | {route.length:.1f} "
                f"| {'ok' if v.ok else 'FAILED'} ({v.checked} re-checked) "
                f"| {t_poses:.0f}, {t_tr:.0f}, {t_v:.0f} | {os.getloadavg()[0]:.1f} |",
                flush=True,
            )
            if args.json:
                out = Path(args.json)
                out.mkdir(parents=True, exist_ok=True)
                (out / f"{name}_{order_name}.json").write_text(json.dumps(path.to_dict()))
            for t in path.blocked:
                print(f"  {name} {order_name} {t.from_id}->{t.to_id}: {t.reason}")


if __name__ == "__main__":
    main()
