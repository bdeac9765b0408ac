"""What ``weldplan plan`` and ``weldplan demo`` share: the run, from the options to the files.

Every output path is checked before any work (:func:`weldplan.io.outputset.check_outputs`); the
run renders every output in memory, and writes the files only after the route passed the
independent verification, as one set (:func:`weldplan.io.outputset.write_outputs`: temporaries,
then renames, rolled back on failure). A run that fails, at any stage, leaves existing output files
exactly as they were.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import logging
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from weldplan.commands._planning_args import (
    add_planning_arguments,
    config_from_args,
    positive_gb,
    positive_mm,
    seed_type,
)
from weldplan.commands._progress import ProgressBars
from weldplan.commands._summary import _gap_rounds, smooth_rows, summary_table
from weldplan.errors import WeldplanError

#: what plan, demo, verify and the tests import from here (the options and the summary live in
#: :mod:`weldplan.commands._planning_args` and :mod:`weldplan.commands._summary`)
__all__ = [
    "_gap_rounds",
    "add_planning_arguments",
    "config_from_args",
    "positive_gb",
    "positive_mm",
    "run_planning",
    "seed_type",
    "smooth_rows",
    "summary_table",
]

log = logging.getLogger(__name__)

#: ``--smooth`` with ``--tool`` or ``--robot`` (docs/smooth-paths.md): what the later stages read
SMOOTH_WITH_TOOL_WARNING = (
    "--smooth with --tool/--robot: the tool poses, tool transitions, robot route, robot "
    "program and the 3D pages follow the polyline, not the smooth path; only the route "
    "CSV/JSON (and a post without --robot) carry the smooth waypoints"
)


def _local_workers(args: argparse.Namespace) -> int:
    """Worker processes on this machine, each holding the cell (1: planning in this process)."""
    dask = getattr(args, "dask", None)
    if dask:
        return max(2, args.jobs) if dask == "local" else 1
    return args.jobs


def _outputs(args: argparse.Namespace) -> dict[str, Path]:
    """Every file the run will write, checked before any work is done."""
    from weldplan.io.export import POSTS
    from weldplan.io.timings import timings_path

    out = {"csv": Path(args.output)}
    if args.json:
        out["json"] = Path(args.json)
        out["timings"] = timings_path(args.json)  # the run's measured times, apart
    if args.html:
        out["html"] = Path(args.html)
    if args.post:
        out["post"] = (
            Path(args.post_file)
            if args.post_file
            else out["csv"].with_suffix(POSTS[args.post].suffix)
        )
    elif args.post_file:
        raise WeldplanError("--post-file needs --post rapid|krl")
    if getattr(args, "robot", None) and args.post == "krl":  # KRL's data list beside the .src
        out["post_dat"] = out["post"].with_suffix(".dat")
    if getattr(args, "tool_csv", None):
        if not getattr(args, "tool", None):
            raise WeldplanError("--tool-csv needs --tool")
        out["tool_csv"] = Path(args.tool_csv)
    for kind in ("trajectory", "robot_html"):
        if getattr(args, kind, None):
            out[kind] = Path(getattr(args, kind))
    seen: dict[Path, str] = {}
    for kind, path in out.items():
        key = path.resolve()
        if key in seen:
            raise WeldplanError(f"{path}: given for both {seen[key]} and {kind}")
        seen[key] = kind
    from weldplan.io.outputset import check_outputs

    check_outputs(out)
    return out


def run_planning(
    args: argparse.Namespace,
    make_cell: Callable[[], Any],
    *,
    title: str,
    note: str | None = None,
    show_cell: bool = False,
    joint_points: Callable[[], Any] | None = None,
) -> int:
    """Build the cell, plan, verify, write; print the summary. Returns the exit code.

    ``show_cell`` prints the cell's summary (part, grid, virtual joints) before the route's.
    ``joint_points()`` gives the joints' ``(n, 3)`` positions (mm) cheaply, before the cell is
    built, for the size check (:mod:`weldplan.weld.sizing`).
    """
    from weldplan.commands._robot import robot_from_args
    from weldplan.commands._tool import tool_from_args
    from weldplan.weld.verify import verify_route

    outputs = _outputs(args)
    config = config_from_args(args)
    tool = tool_from_args(args)  # a bad --tool fails before the (slow) cell is built
    robot = robot_from_args(args)  # so does a bad --robot
    warnings = run_warnings(args)
    for w in warnings:
        print(f"weldplan: warning: {w}", file=sys.stderr)
    if joint_points is not None:
        _check_size(args, config, joint_points())
    bars = ProgressBars(enabled=False if args.quiet else None)
    t_all = time.perf_counter()
    times: dict[str, float] = {}
    legs: dict[str, Any] = {}
    leg_cost: Callable[[Any], Any] | None = None
    if robot is not None and getattr(args, "cost", "length") == "time":
        from weldplan.commands._robot_cost import time_leg_cost

        def leg_cost(cell: Any) -> Any:  # the robot's leg times, before the order exists
            legs["legs"], legs["robot"] = time_leg_cost(args, cell, tool[0], robot)  # type: ignore[index]
            return legs["legs"].cost

    cell, route = _plan(args, config, make_cell, bars, times, leg_cost)
    if legs:
        from weldplan.commands._robot_cost import with_time_stats

        route = with_time_stats(route, legs["legs"], tuple(str(i) for i in cell.joints.ids))
        robot = legs["robot"]

    with bars.stage("verify") as st:
        report = verify_route(route, cell.part, joints=cell.joints)
    times["verify"] = st.seconds
    if not report.ok:
        print(f"weldplan: {report.describe()}; nothing written", file=sys.stderr)
        return 1
    staged = _tool_robot_stages(args, cell, route, tool, robot, outputs, bars, times)
    if staged is None:
        return 1
    route, extra_rows, texts, robot_skipped = staged
    if warnings:
        route = with_warnings(route, warnings)

    with bars.stage("export") as st:
        _write(args, outputs, route, cell, None if tool is None else tool[0], texts)
    times["export"] = st.seconds
    times["total"] = time.perf_counter() - t_all
    if not args.quiet:
        if show_cell and hasattr(cell, "format_summary"):
            print(cell.format_summary())
            print()
        print(
            summary_table(
                route, times, outputs, title=title, report=report, note=note, extra=extra_rows
            )
        )
    code = _partial_code(route)
    if robot_skipped and code == 0:
        from weldplan.errors import EXIT_PARTIAL

        print(f"weldplan: {len(robot_skipped)} weld(s) not in the robot program", file=sys.stderr)
        code = EXIT_PARTIAL
    return code


def run_warnings(args: argparse.Namespace) -> list[str]:
    """What the run says before it starts, on stderr, and records in the route JSON
    (``settings["warnings"]``): options whose combination does less than a reader expects."""
    out = []
    if getattr(args, "smooth", False) and (
        getattr(args, "tool", None) or getattr(args, "robot", None)
    ):
        out.append(SMOOTH_WITH_TOOL_WARNING)
    return out


def with_warnings(route: Any, warnings: list[str]) -> Any:
    """``route`` with ``warnings`` added to ``settings["warnings"]`` (a new Route)."""
    settings = dict(route.settings)
    settings["warnings"] = [*settings.get("warnings", []), *warnings]
    return dataclasses.replace(route, settings=settings)


def _tool_robot_stages(
    args: argparse.Namespace,
    cell: Any,
    route: Any,
    tool: tuple[Any, dict[str, Any]] | None,
    robot: Any,
    outputs: dict[str, Path],
    bars: ProgressBars,
    times: dict[str, float],
) -> tuple[Any, list[tuple[str, str]], dict[str, str], tuple[str, ...]] | None:
    """The weld poses (with a tool) and the robot stage (with a robot) on the verified route.

    Returns
    -------
    route, rows, texts, skipped
        The route carrying what the stages added, their summary rows, the texts the robot
        stage rendered (programs, trajectory), the welds the robot program leaves out; ``None``
        when the poses fail their re-check (said on stderr).
    """
    extra_rows: list[tuple[str, str]] = []
    texts: dict[str, str] = {}
    skipped: tuple[str, ...] = ()
    reach = None
    if robot is not None:  # the robot's reach test for the weld poses
        from weldplan.commands._robot import pose_acceptance

        reach = pose_acceptance(args, cell, route, tool[0], robot)  # type: ignore[index]
    if tool is not None:
        staged = _pose_stage(args, cell, route, tool, bars, times, reach and reach.accept)
        if staged is None:
            return None
        route, extra_rows = staged
    if robot is not None:
        from weldplan.commands._robot import robot_stage

        with bars.stage("robot") as st:
            stage = robot_stage(args, cell, route, tool[0], robot, outputs, reach)  # type: ignore[index]
        times["robot"] = st.seconds
        extra_rows += stage.rows
        texts = stage.texts
        route = stage.route  # with the robot route, for the JSON
        skipped = tuple(stage.skipped)
    return route, extra_rows, texts, skipped


def _pose_stage(
    args: argparse.Namespace,
    cell: Any,
    route: Any,
    tool: tuple[Any, dict[str, Any]],
    bars: ProgressBars,
    times: dict[str, float],
    accept: Any = None,
) -> tuple[Any, list[tuple[str, str]]] | None:
    """The weld poses and their independent re-check; ``None`` (said on stderr) when the re-check
    fails, else the route carrying the poses and the summary rows."""
    from weldplan.commands._tool import plan_poses, pose_rows

    with bars.stage("poses") as st:
        route, check = plan_poses(args, cell, route, *tool, accept=accept)
    times["poses"] = st.seconds
    if not check.ok:
        print(
            f"weldplan: weld poses failed the independent re-check: "
            f"{'; '.join(f'{i}: {r}' for i, r in check.failures[:5])}; nothing written",
            file=sys.stderr,
        )
        return None
    return route, pose_rows(route, check)


def _check_size(args: argparse.Namespace, config: Any, xyz: Any) -> None:
    """Refuse up front a run whose grid or pair work would not fit (:mod:`weldplan.weld.sizing`)."""
    from weldplan.weld.sizing import check_size

    check_size(
        xyz,
        pitch=config.pitch,
        margin=config.margin,
        n_joints=len(xyz),
        candidates=config.candidates,
        memory_limit=config.memory_limit,
        cli=True,
        workers=_local_workers(args),
    )


def _plan(
    args: argparse.Namespace,
    config: Any,
    make_cell: Callable[[], Any],
    bars: ProgressBars,
    times: dict[str, float],
    leg_cost: Callable[[Any], Any] | None = None,
) -> tuple[Any, Any]:
    """The cell and the route, with the executor the options ask for (``times`` filled);
    ``leg_cost(cell)``: what the sequencer minimises instead of length (``--cost time``)."""
    from weldplan.weld.pipeline import plan_route

    with contextlib.ExitStack() as stack:
        executor = None
        dask = getattr(args, "dask", None)
        if dask:  # reach the scheduler first: a wrong address fails in seconds, not after the cell
            from weldplan.weld.parallel import dask_executor

            executor = stack.enter_context(dask_executor(dask, workers=max(2, args.jobs)))
        with bars.stage("cell") as st:
            cell = make_cell()
        times["cell"] = st.seconds
        if not dask and args.jobs > 1:
            from weldplan.weld.parallel import process_pool

            executor = stack.enter_context(process_pool(cell, args.jobs))
        try:
            extra = {} if leg_cost is None else {"leg_cost": leg_cost(cell)}
            route = plan_route(
                cell, config=config, rng=args.seed, executor=executor, progress=bars, **extra
            )
        finally:
            bars.close()
    for k in ("straight", "local", "sequence", "smooth"):
        if k in route.stats["seconds"]:
            times[k] = route.stats["seconds"][k]
    return cell, route


def _write(
    args: argparse.Namespace,
    outputs: dict[str, Path],
    route: Any,
    cell: Any,
    tool: Any,
    staged: dict[str, str] | None = None,
) -> None:
    """Render every output in memory, then write them as one set (:mod:`weldplan.io.outputset`).

    ``staged``: texts a stage already rendered (the robot stage's programs and trajectory); they
    replace the point-tip post."""
    from weldplan.io.export import render_post, to_csv_text
    from weldplan.io.outputset import write_outputs
    from weldplan.io.timings import route_json_texts
    from weldplan.viz.viewer import static_html

    texts = {"csv": to_csv_text(route)}
    if "json" in outputs:
        texts["json"], texts["timings"] = route_json_texts(route)
    if "html" in outputs:
        texts["html"] = static_html(route, cell.part, tool=tool)
    if "post" in outputs and "post" not in (staged or {}):
        texts["post"] = render_post(route, args.post, cell)
    if "tool_csv" in outputs:
        from weldplan.tool.path_csv import route_tool_csv

        texts["tool_csv"] = route_tool_csv(route)
    texts.update(staged or {})
    write_outputs({path: texts[kind] for kind, path in outputs.items()})


def _partial_code(route: Any) -> int:
    """0, or EXIT_PARTIAL with one stderr line per cause: joints skipped, welds without a pose."""
    from weldplan.errors import EXIT_OK, EXIT_PARTIAL

    def listed(ids: list[str]) -> str:
        return ", ".join(ids[:10]) + (", ..." if len(ids) > 10 else "")

    code = EXIT_OK
    skipped = [s["id"] for s in route.stats.get("skipped") or []]
    if skipped:
        print(
            f"weldplan: partial route: {len(skipped)} joint(s) skipped ({listed(skipped)})",
            file=sys.stderr,
        )
        code = EXIT_PARTIAL
    if route.tool.get("poses"):
        missed = [str(p["id"]) for p in route.tool["poses"]["poses"] if p["status"] != "ok"]
        if missed:
            print(
                f"weldplan: {len(missed)} weld(s) without a free tool pose ({listed(missed)})",
                file=sys.stderr,
            )
            code = EXIT_PARTIAL
    from weldplan.commands._tool import transitions_partial

    return EXIT_PARTIAL if transitions_partial(route) else code
