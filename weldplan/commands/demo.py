"""``weldplan demo``: plan the embedded demo cell end to end (route.csv and route.html)."""

from __future__ import annotations

import argparse

from weldplan.commands._planning import add_planning_arguments, run_planning
from weldplan.commands._planning_args import add_cell_stage_arguments
from weldplan.commands._types import positive_mm

#: what verify imports from here
__all__ = ["add_arguments", "positive_mm", "run"]

HELP = "plan, verify and export the embedded demo cell (15 joints of Wang et al. 2017)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_cell_stage_arguments(p, only=("pitch", "margin"))
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
