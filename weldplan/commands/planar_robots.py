"""``weldplan planar robots SCENARIO``: paper 001's three robots on a grid scenario.

Plans each robot's global path (``--global-planner``, HAFSA by default), runs the time-stepped
simulation with local replanning, prints arrival steps, replans and the minimum distance, and
writes ``--plot`` (PNG) and ``--gif`` (animation).
"""

from __future__ import annotations

import argparse
import sys

from weldplan.errors import WeldplanError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("planar robots")
    g.add_argument("--global-planner", default="hafsa", help="robots: optimiser or 'astar'")
    g.add_argument("--safety", type=float, default=None, help="robots: safety radius (cells)")
    g.add_argument("--gif", default=None, help="robots: write an animation (GIF) here")


def run(args: argparse.Namespace) -> int:
    from weldplan.planar.multirobot import SAFETY_RADIUS, simulate_robots
    from weldplan.planar.scenarios import load_scenario

    if len(args.more) != 1:
        raise WeldplanError("usage: weldplan planar robots SCENARIO [options]")
    sc = load_scenario(args.more[0])
    if sc.grid is None:
        raise WeldplanError(f"{sc.name} has no occupancy grid (field obstacles: add a grid)")
    safety = SAFETY_RADIUS if args.safety is None else args.safety
    r = simulate_robots(sc, algorithm=args.global_planner.lower(), safety=safety, rng=args.seed)
    for k in range(len(r.paths)):
        sys.stdout.write(
            f"robot {k}: {r.paths[k][0]} -> {r.paths[k][-1]}, global path by {r.planner[k]}, "
            f"arrives at step {r.arrival[k]}, {r.replans[k]} local replans\n"
        )
    ok = min(r.min_distance) > r.safety
    sys.stdout.write(
        f"minimum distance between robots {min(r.min_distance):.3f} "
        f"({'>' if ok else '<='} safety radius {r.safety:g})\n"
    )
    if args.plot:
        from weldplan.viz.robots import plot_robots

        plot_robots(sc, r, args.plot)
    if args.gif:
        from weldplan.viz.robots import animate_robots

        animate_robots(sc, r, args.gif)
    return 0 if (ok and r.all_arrived) else 1
