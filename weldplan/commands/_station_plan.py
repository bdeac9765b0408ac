"""``weldplan plan station.toml`` with several ``[[robot]]``: plan the station through
:func:`weldplan.plan` (a :class:`~weldplan.multi.station.StationPlan`), write every robot's
files and the station JSON (and, with ``--html``, the station's page and Gantt PNG) as one set,
whole or not at all (:mod:`weldplan.multi.saved`), print the station's summary. Exit 0, or 3
when welds are left out (unreached, or left out by a robot's plan) or the replay found robots
too close."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from typing import Any


def run_station(args: argparse.Namespace, station: Any, *, title: str) -> int:
    """Plan ``station`` (several robots), write its files, print the summary; the exit code."""
    from weldplan.commands._planning import plan_and_write
    from weldplan.multi.bases import check_bases
    from weldplan.multi.saved import robot_plans, station_paths, write_station

    station = _named(station)
    paths = station_paths(station.outputs, len(station.robots))  # checked before any work
    check_bases(station)
    splan, seconds = plan_and_write(args, station, lambda plan: write_station(plan, paths))
    plans = robot_plans(splan)
    if not args.quiet:
        times = {**splan.stats.get("seconds", {}), **seconds}
        print(_summary(splan, plans, paths, times, title))
    return _exit_code(splan, plans)


def _named(station: Any) -> Any:
    """The station named after its route CSV (as one robot's program is), unless named."""
    if station.name is not None:
        return station
    if station.outputs.csv is None:
        from weldplan.errors import WeldplanError

        raise WeldplanError("no route CSV to write: give -o (or [output] csv in the station)")
    return dataclasses.replace(station, name=station.outputs.csv.stem)


def _summary(splan: Any, plans: Any, paths: Any, times: dict[str, float], title: str) -> str:
    from weldplan.station.summary import station_rows

    rows = station_rows(splan, plans)
    rows.append(("time", ", ".join(f"{k} {v:.2f} s" for k, v in times.items())))
    rows.append(("station JSON", str(paths.station)))
    if paths.html is not None:
        rows.append(("station page", f"{paths.html}, Gantt chart {paths.gantt}"))
    for k, files in enumerate(paths.robots):
        if plans[k] is not None:
            rows.append((f"robot{k + 1} files", ", ".join(str(p) for p in files.values())))
    w = max(len(k) for k, _ in rows)
    return "\n".join([title, "-" * len(title), *(f"{k:<{w}}  {v}" for k, v in rows)])


def _exit_code(splan: Any, plans: Any) -> int:
    """0, or EXIT_PARTIAL with one stderr line per cause
    (:func:`weldplan.station.summary.station_partial`)."""
    from weldplan.errors import EXIT_OK, EXIT_PARTIAL
    from weldplan.station.summary import station_partial

    lines = station_partial(splan, plans)
    for line in lines:
        print(f"weldplan: {line}", file=sys.stderr)
    return EXIT_PARTIAL if lines else EXIT_OK
