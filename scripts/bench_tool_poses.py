"""Benchmark: a verified gun pose per weld on the demo cell and the car2 synthetic stations.

Usage (from the repository root; car2 is scaled to 4500 mm as in docs/bench-scale.md)::

    python scripts/bench_tool_poses.py [--stations demo,car2_50,car2_200] [--order route|file]

For each station: welds with a verified free pose / total, seconds of the pose search per weld,
the total orientation change along the visiting order (the DP's objective) next to the change of
the nominal frames (spin 0, tilt 0 everywhere: what a pose without a spin choice would turn), and
the re-check of every ok pose. Prints a markdown table with the load average.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

import weldplan
from weldplan.tool import plan_weld_poses, shared_spot_gun, verify_poses
from weldplan.tool.orient import nominal_frames, rotation_angles
from weldplan.tool.result import quat_wxyz

ROOT = Path(__file__).resolve().parents[1]
CAR2 = ROOT.parent / "shared" / "data" / "bodies" / "car2.obj"


def _cell(name: str):
    if name == "demo":
        return weldplan.demo_cell()
    joints = ROOT / "assets" / "car2" / f"car2_synthetic_{name.split('_')[1]}.csv"
    return weldplan.load_cell(CAR2, joints, length=4500)


def _nominal_rotation(poses) -> float:
    """Degrees turned along the ok welds (the DP's chain) by their nominal frames."""
    q = quat_wxyz(nominal_frames(np.array([p.approach for p in poses.poses if p.ok])))
    return float(sum(rotation_angles(q[i][None], q[i + 1][None])[0, 0] for i in range(len(q) - 1)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stations", default="demo,car2_50,car2_200")
    ap.add_argument("--order", choices=("route", "file"), default="route")
    ap.add_argument("--json", help="folder to write each station's WeldPoses JSON to")
    args = ap.parse_args()
    gun = shared_spot_gun()
    print(f"{platform.node()} ({os.cpu_count()} CPUs), load average {os.getloadavg()}")
    print(f"tool: {gun.name}, {len(gun.faces)} triangles, reach {gun.reach:.0f} mm\n")
    print(
        "| station | order | welds ok / total | pose s / weld | rotation deg (DP) "
        "| rotation deg (nominal frames, same welds) | re-check "
        "| collide / distance queries | load |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.stations.split(","):
        cell = _cell(name)
        load0 = os.getloadavg()
        src = weldplan.plan_route(cell, rng=0) if args.order == "route" else cell.joints
        t = time.perf_counter()
        poses = plan_weld_poses(cell, src, gun)
        dt = time.perf_counter() - t
        ver = verify_poses(poses, cell.part, gun)
        n = len(poses.poses)
        print(
            f"| {name} | {args.order} | {poses.n_ok} / {n} | {dt / n:.2f} "
            f"| {poses.total_rotation:.1f} | {_nominal_rotation(poses):.1f} "
            f"| {'ok' if ver.ok else 'FAILED'} ({ver.checked}) "
            f"| {poses.stats['collision_queries']} / {poses.stats['distance_queries']} "
            f"| {' '.join(f'{x:.1f}' for x in load0)} / "
            f"{' '.join(f'{x:.1f}' for x in os.getloadavg())} |",
            flush=True,
        )
        misses = [p.miss for p in poses.poses if not p.ok and p.miss is not None]
        near = sum(m.contacts == 0 for m in misses)
        ahead = sum(m.contacts > 0 and m.tool_point[2] > 0 for m in misses)
        behind = len(misses) - near - ahead
        print(
            f"<!-- {name}: {len(misses)} misses: {ahead} hit ahead of the TCP (fixed electrode / "
            f"C-arm: part behind the sheet), {behind} behind it (moving electrode, body), "
            f"{near} only short of the clearance -->"
        )
        if args.json:
            Path(args.json).mkdir(parents=True, exist_ok=True)
            (Path(args.json) / f"{name}.json").write_text(poses.to_json())


if __name__ == "__main__":
    main()
