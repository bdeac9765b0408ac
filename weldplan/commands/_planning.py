"""What ``weldplan plan`` and ``weldplan demo`` share: options -> station -> plan -> files.

The run is :func:`weldplan.plan` on the :class:`~weldplan.station.model.Station` the options (or
the station file) describe. Every output path is checked before any work
(:func:`weldplan.station.outputs.output_paths`); the plan renders every output in memory and
writes the files only after every stage passed its independent re-check, as one set
(:func:`weldplan.station.outputs.write_plan`). A run that fails, at any stage, leaves existing
output files exactly as they were.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any

from weldplan.commands._planning_args import (
    add_planning_arguments,
    config_from_args,
    positive_gb,
    positive_mm,
    seed_type,
)
from weldplan.commands._progress import ProgressBars
from weldplan.station.pipeline import SMOOTH_WITH_TOOL_WARNING
from weldplan.station.summary import _gap_rounds, plan_rows, smooth_rows, summary_table

#: what plan, demo, verify and the tests import from here
__all__ = [
    "SMOOTH_WITH_TOOL_WARNING",
    "_gap_rounds",
    "add_planning_arguments",
    "config_from_args",
    "plan_and_write",
    "positive_gb",
    "positive_mm",
    "run_planning",
    "run_warnings",
    "seed_type",
    "smooth_rows",
    "summary_table",
]


def _local_workers(args: argparse.Namespace, jobs: int) -> int:
    """Worker processes on this machine, each holding the cell (1: planning in this process)."""
    dask = getattr(args, "dask", None)
    if dask:
        return max(2, jobs) if dask == "local" else 1
    return jobs


@contextlib.contextmanager
def _executor(args: argparse.Namespace, jobs: int) -> Iterator[Any]:
    """The Dask executor ``--dask`` asks for (reached first: a wrong address fails in seconds,
    not after the cell), else None (the plan makes its own process pool for ``jobs`` > 1)."""
    dask = getattr(args, "dask", None)
    if not dask:
        yield None
        return
    from weldplan.weld.parallel import dask_executor

    with dask_executor(dask, workers=max(2, jobs)) as ex:
        yield ex


def plan_and_write(
    args: argparse.Namespace, station: Any, write: Callable[[Any], None]
) -> tuple[Any, dict[str, float]]:
    """:func:`weldplan.plan` on ``station`` (one robot or several) with the run's options (the
    seed, ``--jobs`` / ``--dask``, progress bars unless ``--quiet``), then ``write(plan)`` as
    the ``export`` stage; returns the plan and the seconds of ``export`` and of the whole run
    (``total``)."""
    import weldplan

    bars = ProgressBars(enabled=False if args.quiet else None)
    t_all = time.perf_counter()
    with _executor(args, station.jobs) as executor:
        try:
            rng = station.seed if args.seed is None else args.seed
            plan = weldplan.plan(station, rng=rng, executor=executor, progress=bars)
        finally:
            bars.close()
    with bars.stage("export") as st:
        write(plan)
    return plan, {"export": st.seconds, "total": time.perf_counter() - t_all}


def run_planning(
    args: argparse.Namespace, station: Any, *, title: str, note: str | None = None,
    show_cell: bool = False,
) -> int:  # fmt: skip
    """Plan ``station``, write its files, print the summary; returns the exit code."""
    from weldplan.station.outputs import write_plan

    station, outputs = _prepare(args, station)
    result, seconds = plan_and_write(args, station, lambda plan: write_plan(plan, outputs))
    times = {**result.times, **seconds}
    if not args.quiet:
        if show_cell and hasattr(result.cell, "format_summary"):
            print(result.cell.format_summary() + "\n")
        kw = {"title": title, "report": result.verification, "note": note}
        print(summary_table(result.route, times, outputs, extra=plan_rows(result), **kw))
    return _partial_code(result)


def _prepare(args: argparse.Namespace, station: Any) -> tuple[Any, dict[str, Any]]:
    """Before any work: the program's name, the output paths checked, the warnings said, the
    size checked (:func:`weldplan.station.pipeline.check_station_size`)."""
    import dataclasses

    from weldplan.station.outputs import output_paths
    from weldplan.station.pipeline import check_station_size
    from weldplan.station.pipeline import run_warnings as station_warnings

    if station.name is None:  # the program is named after the file it is written to
        stem = (station.outputs.post_file or station.outputs.csv).stem
        station = dataclasses.replace(station, name=stem)
    spec = station.robot
    outputs = output_paths(
        station.outputs, robot=spec is not None and spec.urdf is not None, tool=spec is not None
    )
    for w in station_warnings(station):
        print(f"weldplan: warning: {w}", file=sys.stderr)
    check_station_size(station, cli=True, workers=_local_workers(args, station.jobs))
    return station, outputs


def run_warnings(args: argparse.Namespace) -> list[str]:
    """What the run says before it starts (:func:`weldplan.station.pipeline.run_warnings`), from
    the options."""
    smooth = getattr(args, "smooth", False)
    tool = getattr(args, "tool", None) or getattr(args, "robot", None)
    return [SMOOTH_WITH_TOOL_WARNING] if smooth and tool else []


def _partial_code(result: Any) -> int:
    """0, or EXIT_PARTIAL with one stderr line per cause (:meth:`weldplan.station.Plan.partial`)."""
    from weldplan.errors import EXIT_OK, EXIT_PARTIAL

    lines = result.partial()
    for line in lines:
        print(f"weldplan: {line}", file=sys.stderr)
    return EXIT_PARTIAL if lines else EXIT_OK
