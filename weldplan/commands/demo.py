"""``weldplan demo``: plan the embedded demo cell end to end (route.csv and route.html)."""

from __future__ import annotations

import argparse

from weldplan.commands._planning import (  # positive_mm: also imported from here by plan, verify
    add_planning_arguments,
    positive_mm,
    run_planning,
)

HELP = "plan, verify and export the embedded demo cell (15 joints of Wang et al. 2017)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--pitch", type=positive_mm, default=5.0, help="voxel side in mm (default 5)")
    p.add_argument(
        "--clearance", type=positive_mm, default=5.0, help="torch-tip clearance in mm (default 5)"
    )
    p.add_argument(
        "--margin",
        type=positive_mm,
        default=150.0,
        help="margin around the joints in mm (default 150)",
    )
    add_planning_arguments(p, default_output="route.csv")
    p.set_defaults(html="route.html")
    p.add_argument(
        "--no-html", dest="html", action="store_const", const=None, help="do not write route.html"
    )


def run(args: argparse.Namespace) -> int:
    from weldplan.commands._station_args import station_from_args
    from weldplan.station.model import PartSpec

    return run_planning(
        args,
        station_from_args(args, PartSpec()),  # the embedded demo part and joints
        title="weldplan demo (Wang et al. 2017, 15 joints)",
        note="the paper: lower bound 595.10 mm, its collision-free route 599.72 mm (+0.78 %), "
        "measured between joints without approach segments",
        show_cell=True,
    )
