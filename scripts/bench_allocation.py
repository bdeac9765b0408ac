"""Benchmark: weld allocation among several robots on synthetic stations (weldplan.multi).

Usage (from the repository root)::

    python scripts/bench_allocation.py [--welds 100,200,400] [--robots 2,4,4] [--seed 0]

Each station: ``W`` welds spread over a 3 x 1.6 x 0.6 m body, robots at the corners of a
2.4 x 3.6 m rectangle about it, a weld served by every robot within 2.6 m of it (and always by
the nearest), 0.5 s a weld; each robot's move times are the rest-to-rest joint-space bounds
(:func:`weldplan.robot.legtime.rest_to_rest_bound`, KR 150-class limits) between synthetic
configurations that vary smoothly with the weld's position. Prints the table of
:meth:`weldplan.multi.AllocationReport.lines` (one robot, nearest robot, ours, the lower bound),
the CPU seconds of the whole report and the load average.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from weldplan.multi import ReachMap, allocation_report
from weldplan.robot.legtime import rest_to_rest_bound

#: rad/s: joint velocity limits of a heavy six-axis arm (KR 150 class); accelerations 3x
VEL = np.radians([105.0, 101.0, 107.0, 136.0, 129.0, 206.0])
#: mm: the robots' bases (up to four)
BASES = np.array([[-1200, -1800, 0], [1200, -1800, 0], [-1200, 1800, 0], [1200, 1800, 0.0]])
#: mm: a robot serves the welds within this distance of its base
REACH_MM = 2600.0


def station(W: int, R: int, seed: int):
    """``(ReachMap, weld_time (R, W) s, travel (R, W, W) s)`` of the module docstring."""
    g = np.random.default_rng(seed)
    pos = g.uniform([-1500, -800, 0], [1500, 800, 600], (W, 3))
    bases = BASES[:R]
    d = np.linalg.norm(pos[None] - bases[:, None], axis=2)
    ok = d < REACH_MM
    ok[np.argmin(d, axis=0), np.arange(W)] = True
    Q = np.stack(
        [
            np.c_[
                np.arctan2(pos[:, 1] - b[1], pos[:, 0] - b[0]),
                (pos - b) @ g.normal(size=(3, 5)) / 2000,
            ]
            for b in bases
        ]
    )
    T = np.stack([rest_to_rest_bound(q[:, None] - q[None], VEL, 3.0 * VEL) for q in Q])
    return ReachMap.of(ok, bases=bases, positions=pos), np.full((R, W), 0.5), T


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--welds", default="100,200,400")
    ap.add_argument("--robots", default="2,4,4")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    for W, R in zip(map(int, a.welds.split(",")), map(int, a.robots.split(",")), strict=True):
        reach, wt, T = station(W, R, a.seed)
        c0 = time.process_time()
        rep = allocation_report(reach, wt, T, rng=a.seed)
        cpu = time.process_time() - c0
        unique = int((reach.ok.sum(axis=0) == 1).sum())
        print(f"\n{W} welds, {R} robots ({unique} served by one robot only): {cpu:.1f} CPU s")
        print("\n".join(rep.lines()))
        util = ", ".join(f"{u:.3f}" for u in rep.ours.utilisation)
        print(f"utilisation {util}; {rep.ours.stats['kicks']} kicks")
    print(f"\nload average {os.getloadavg()}")


if __name__ == "__main__":
    main()
