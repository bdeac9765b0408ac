"""``weldplan bench NAME``: the runnable reproductions of the papers' tables."""

from __future__ import annotations

import argparse
from importlib import import_module

HELP = "reproduce a paper's table or measure a target (writes markdown and PNG)"

#: benchmark name -> module with ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``
BENCHES: dict[str, str] = {
    "grid": "weldplan.bench.grid",
    "collision": "weldplan.bench.collision",
    "functions": "weldplan.bench.functions",
    "mealpy": "weldplan.bench.mealpy_peer",
    "local": "weldplan.bench.local",
    "sequence": "weldplan.bench.sequence",
    "route": "weldplan.bench.route",
    "scale": "weldplan.bench.scale",
    "planar": "weldplan.bench.planar",
    "tour": "weldplan.bench.tour",
    "queries": "weldplan.bench.queries",
    "tool": "weldplan.bench.tool",
    "robot": "weldplan.bench.robot",
    "gun-oracle": "weldplan.bench.gun_oracle",
    "station": "weldplan.bench.station",
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="bench", metavar="NAME")
    sub.required = True
    for name, module_name in BENCHES.items():
        module = import_module(module_name)
        p = sub.add_parser(name, help=module.HELP, description=module.HELP)
        p.add_argument("--out", default="bench-results", help="folder for the table and plots")
        module.add_arguments(p)
        p.set_defaults(_bench_run=module.run)


def run(args: argparse.Namespace) -> int:
    return int(args._bench_run(args) or 0)
