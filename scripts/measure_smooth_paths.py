"""Measure: the smooth legs of ``weldplan plan --smooth`` on the demo and on car2_50 (issue 15).

Usage (from the repository root; car2 needs ``../shared/data/bodies/car2.obj``)::

    python scripts/measure_smooth_paths.py demo
    python scripts/measure_smooth_paths.py car2 [--joints assets/car2/car2_synthetic_50.csv]

Plans the route (default pipeline, seed 0), smooths it ``--repeat`` times
(:func:`weldplan.weld.smoothing.smooth_route`; the time it adds is the minimum), verifies the
smoothed route independently and prints one Markdown row per curved leg: polyline and curve
length, waypoints, max curvature (and radius), min clearance and its margin over the clearance
(docs/smooth-paths.md holds a run).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from weldplan.weld.pipeline import plan_route
from weldplan.weld.smoothing import smooth_route
from weldplan.weld.verify import verify_route

ROOT = Path(__file__).resolve().parents[1]
CAR2 = ROOT.parent / "shared" / "data" / "bodies" / "car2.obj"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cell", choices=("demo", "car2"))
    ap.add_argument("--joints", default=str(ROOT / "assets/car2/car2_synthetic_50.csv"))
    ap.add_argument("--spacing", type=float, default=5.0, help="mm (5)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    if args.cell == "demo":
        from weldplan.weld.cell import demo_cell

        cell = demo_cell()
    else:
        from weldplan.weld.cell import load_cell

        cell = load_cell(CAR2, args.joints, length=4500)
    t = time.perf_counter()
    route = plan_route(cell, rng=args.seed)
    t_plan = time.perf_counter() - t
    times = []
    for _ in range(args.repeat):
        t = time.perf_counter()
        sm = smooth_route(route, cell, spacing=args.spacing)
        times.append(time.perf_counter() - t)
    rep = verify_route(sm, cell.part)
    s = sm.stats["smooth"]
    print(
        f"{args.cell}: plan {t_plan:.2f} s; smoothing {min(times):.3f} s (min of {args.repeat}, "
        f"median {np.median(times):.3f}); {s['smoothed']} of {s['curved']} curved legs smoothed, "
        f"{len(sm.legs)} legs; max curvature {s['max_curvature']:.4f} 1/mm; min clearance "
        f"margin {s['min_clearance_margin']:.4f} mm; length {route.length:.2f} -> "
        f"{s['length']:.2f} mm; {rep.describe()}"
    )
    print(
        "| leg | from -> to | polyline mm | curve mm | waypoints | max curvature 1/mm (radius mm)"
        " | min clearance mm (margin) | status |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for f in s["legs"]:
        if not f["curved"]:
            continue
        k = f["max_curvature"]
        radius = f"{1 / k:.1f}" if k > 0 else "inf"
        margin = f["min_clearance"] - s["clearance"]
        print(
            f"| {f['leg']} | {f['from_id']} -> {f['to_id']} | {f['polyline_length']:.2f} | "
            f"{f['length']:.2f} | {f['waypoints']} | {k:.4f} ({radius}) | "
            f"{f['min_clearance']:.3f} ({margin:+.4f}) | "
            f"{'smoothed' if f['smoothed'] else f['status']} |"
        )


if __name__ == "__main__":
    main()
