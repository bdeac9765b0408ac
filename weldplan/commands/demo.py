"""``weldplan demo``: the embedded demo cell (Wang et al. 2017's 15 joints on a generated part)."""

from __future__ import annotations

import argparse
import json
import sys

HELP = "load the embedded demo cell and print its summary"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--pitch", type=float, default=5.0, help="voxel side in mm (default 5)")
    parser.add_argument(
        "--clearance", type=float, default=5.0, help="torch-tip clearance in mm (default 5)"
    )
    parser.add_argument(
        "--margin", type=float, default=150.0, help="margin around the joints in mm (default 150)"
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")


def run(args: argparse.Namespace) -> int:
    from weldplan.weld.cell import demo_cell

    cell = demo_cell(pitch=args.pitch, clearance=args.clearance, margin=args.margin)
    if args.json:
        json.dump(cell.summary(), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        sys.stdout.write("weldplan demo cell (joints of Wang et al. 2017, Table 1)\n")
        sys.stdout.write(cell.format_summary() + "\n")
    return 0
