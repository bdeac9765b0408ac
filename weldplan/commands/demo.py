"""``weldplan demo``: plan the embedded demo cell end to end (route.csv and route.html)."""

from __future__ import annotations

import argparse

from weldplan.commands._planning import add_planning_arguments, run_planning

HELP = "plan, verify and export the embedded demo cell (15 joints of Wang et al. 2017)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_planning_arguments(p, default_output="route.csv")
    p.set_defaults(html="route.html")
    p.add_argument(
        "--no-html", dest="html", action="store_const", const=None, help="do not write route.html"
    )


def run(args: argparse.Namespace) -> int:
    def make_cell():
        from weldplan.weld.cell import demo_cell

        return demo_cell()

    return run_planning(args, make_cell, title="weldplan demo (Wang et al. 2017, 15 joints)")
