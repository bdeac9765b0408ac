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
    from weldplan.weld.pipeline import PlanConfig

    PlanConfig(clearance=args.clearance, pitch=args.pitch, margin=args.margin)  # validates

    def make_cell():
        from weldplan.weld.cell import demo_cell

        return demo_cell(pitch=args.pitch, clearance=args.clearance, margin=args.margin)

    return run_planning(
        args,
        make_cell,
        title="weldplan demo (Wang et al. 2017, 15 joints)",
        note="the paper: lower bound 595.10 mm, its collision-free route 599.72 mm (+0.78 %), "
        "measured between joints without approach segments",
        show_cell=True,
        joint_points=_demo_points,
    )


def _demo_points():
    """The demo joints' positions (mm), for the size check before the cell is built."""
    from weldplan.weld import demo_part

    return demo_part.TABLE1_XYZ
