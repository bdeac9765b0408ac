"""``weldplan bench planar``: the 2D papers' comparison tables, with the exact optimum beside.

Protocols (``--protocols``, default all):

``000``
    Paper 000 Table 3: GWO, WOA, PSO, SMA, LRSMA on the three circle maps, population 30,
    30 iterations, spline encoding; minimum, mean and SD of length, mean and maximum time,
    success rate, gap of the mean to the exact optimum. The paper ran 100 runs; ``--runs``.
``003``
    Paper 003 Tables 1-4: ParaPA, PSO in the original frame, PSO (w = 0.7), CPSO, WPSO, MPSO,
    ACO, ABC, MABC on the seven 20 x 20 maps, the two 50 x 50 maps and the 100 x 100 building,
    NP = 50, 200 iterations, segment encoding; mean, SD, worst, optimum of length (over the
    successful runs), success rate, diversity DI (eq. 18) of the final population. The paper
    ran 1000 runs. 003 does not say which ACO it ran; the ACO column is ACO_R (Socha &
    Dorigo 2008, continuous ants with a solution archive, ``weldplan.optim.algorithms.acor``),
    our choice, 50 ants per iteration like the other columns.
``001``
    Paper 001 Table 1 style: AFSA and HAFSA on the 20 x 20 and 40 x 40 grids, 50 fish,
    100 iterations: longest, best, average length and mean time, beside the A* optimum.
``multimodal`` (not in the default list)
    Paper 003 sections 4.3-4.4: k = 3 distinct paths from one ParaPA run on each 20 x 20 map,
    beside the single-best ParaPA (:mod:`weldplan.bench.multimodal`).
``defaults`` (not in the default list)
    The default pipeline of ``weldplan planar`` (seeded LRSMA, repair, polish) against LRSMA
    as printed, on every scenario under ``assets/scenarios`` and seeds ``0..--runs-defaults``:
    gap to the exact any-angle optimum (mean, worst), colliding runs, wall and CPU seconds per
    run (:mod:`weldplan.bench.planar_defaults`). Protocols 000, 003 and 001 also print the
    default pipeline beside the papers' algorithms (a row ``DEFAULT``, a column ``Default``).
``exact``
    The exact planners against third-party data: A* on the Moving AI queries for
    ``--exact-seconds`` per map and the same grid graph by compiled Dijkstra on all of them;
    the visibility graph on the Polyanya arena mesh against the same map as a grid, and on
    the aurora mesh (bounds only, ``--mesh-seconds``). The meshes' ``.scen`` lengths are
    octile grid lengths, not any-angle optima (see the report).

Runs are spread over ``--jobs`` processes. Writes ``planar.md`` and PNGs into ``--out``.
"""

from __future__ import annotations

import argparse
import logging
import os
from pathlib import Path

log = logging.getLogger(__name__)

HELP = "2D planning tables of papers 000, 003 and 001 (and the exact planners' validation)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from weldplan.bench.planar_papers import P003_MAPS

    parser.add_argument("--protocols", default="000,003,001,exact", help="comma-separated")
    parser.add_argument("--runs", type=int, default=20, help="runs per algorithm and map (000)")
    parser.add_argument("--runs-003", type=int, default=10, help="runs per cell for 003")
    parser.add_argument("--runs-001", type=int, default=20, help="runs per cell for 001")
    parser.add_argument("--iters-003", type=int, default=200, help="iterations for 003")
    parser.add_argument("--maps-003", default=",".join(P003_MAPS), help="maps for 003")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes")
    parser.add_argument(
        "--exact-seconds", type=float, default=120.0, help="time for A* per Moving AI map"
    )
    parser.add_argument(
        "--dijkstra-seconds",
        type=float,
        default=None,
        help="time box for the all-queries Dijkstra per Moving AI map (default: no limit)",
    )
    parser.add_argument(
        "--mesh-seconds", type=float, default=300.0, help="time for the aurora mesh queries"
    )
    parser.add_argument(
        "--runs-defaults", type=int, default=10, help="seeds per scenario (defaults)"
    )
    parser.add_argument("--data", default=None, help="folder of the shared data (movingai, ...)")
    from weldplan.bench.multimodal import add_arguments as add_multimodal

    add_multimodal(parser)


def protocol_multimodal(args: argparse.Namespace, out: Path) -> list[str]:
    """003 4.3-4.4: k distinct paths per run (:mod:`weldplan.bench.multimodal`)."""
    from weldplan.bench.multimodal import protocol_multimodal as proto

    return proto(args, out)


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    head = [
        "# weldplan bench planar",
        "",
        f"Machine: {os.cpu_count()} CPUs, load average at start {load[0]:.2f} {load[1]:.2f} "
        f"{load[2]:.2f}; {args.jobs} worker processes.",
        "",
    ]
    from weldplan.bench.planar_defaults import protocol_defaults
    from weldplan.bench.planar_exact import protocol_exact
    from weldplan.bench.planar_papers import protocol_000, protocol_001, protocol_003

    protocols = {
        "000": protocol_000,
        "003": protocol_003,
        "001": protocol_001,
        "exact": protocol_exact,
        "multimodal": protocol_multimodal,
        "defaults": protocol_defaults,
    }
    body: list[str] = []
    for p in [p.strip() for p in args.protocols.split(",") if p.strip()]:
        if p not in protocols:
            from weldplan.errors import WeldplanError

            raise WeldplanError(f"unknown protocol {p!r}; choose from {', '.join(protocols)}")
        log.info("protocol %s", p)
        body += protocols[p](args, out)
        (out / "planar.md").write_text("\n".join(head + body) + "\n")
    print(f"wrote {out / 'planar.md'}")
    return 0
