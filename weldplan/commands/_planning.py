"""What ``weldplan plan`` and ``weldplan demo`` share: options, the run, the summary table.

Every output path is checked before any work (:func:`weldplan.io.outputset.check_outputs`); the
run renders every output in memory, and writes the files only after the route passed the
independent verification, as one set (:func:`weldplan.io.outputset.write_outputs`: temporaries,
then renames, rolled back on failure). A run that fails, at any stage, leaves existing output files
exactly as they were.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from weldplan.commands._progress import ProgressBars
from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)


def add_planning_arguments(p: argparse.ArgumentParser, *, default_output: str | None) -> None:
    """Options of the planning run (outputs, planner, sequencer, seed, jobs, quiet)."""
    if default_output is None:
        p.add_argument("-o", "--output", required=True, help="route CSV to write")
    else:
        p.add_argument(
            "-o", "--output", default=default_output, help=f"route CSV (default {default_output})"
        )
    p.add_argument("--json", metavar="F", help="also write the whole route as JSON")
    p.add_argument("--html", metavar="F", help="also write a self-contained 3D page (meshcat)")
    p.add_argument(
        "--post",
        choices=_post_names(),
        help="also write a robot program next to the CSV (rapid: ABB .mod, krl: KUKA .src)",
    )
    p.add_argument("--post-file", metavar="F", help="where --post writes (default: CSV stem)")
    p.add_argument(
        "--planner",
        default="exact",
        choices=("so-aco", "aco", "exact", "ompl"),
        help="local planner for blocked pairs (default exact: 26-connected A* + the secondary "
        "optimisation, then the refinement; so-aco: the paper's; ompl: OMPL's BIT*, 1 s a pair, on "
        "the same FCL checks; needs the ompl extra)",
    )
    p.add_argument(
        "--no-refine",
        action="store_true",
        help="skip the continuous refinement after the grid planner (with --planner so-aco: the "
        "paper's pipeline as printed; default: refine, shortcuts anywhere on the path re-checked "
        "by FCL)",
    )
    p.add_argument(
        "--smooth",
        action="store_true",
        help="give each leg a smooth path: a C2 curve between its virtual joints, checked at the "
        "clearance and exported as dense waypoints (CSV/JSON kind 'smooth'; RAPID MoveL, KRL "
        "SPLINE); a leg whose curve fails keeps its polyline and the summary says so",
    )
    p.add_argument(
        "--smooth-spacing",
        metavar="MM",
        type=positive_mm,
        default=5.0,
        help="with --smooth: largest spacing of the smooth waypoints, mm (default 5; denser "
        "where a chord would cut into the clearance)",
    )
    p.add_argument(
        "--sequencer",
        default="auto",
        choices=("auto", "fast-tsp", "pso", "exact", "nn"),
        help="joint order: auto = exact (Held-Karp) up to 13 joints, else fast-tsp; pso = the "
        "paper's TSP-PSO + polish (default auto)",
    )
    p.add_argument(
        "--aco",
        metavar="N",
        type=int,
        default=10,
        help="SO-ACO iterations N = ants M (default 10; the paper also runs 50)",
    )
    p.add_argument(
        "--seed", type=seed_type, default=0, help="random seed, an integer >= 0 (default 0)"
    )
    p.add_argument("--jobs", type=int, default=1, help="processes planning local paths (default 1)")
    p.add_argument(
        "--dask",
        metavar="ADDR",
        help="plan local paths on Dask: 'local' starts a LocalCluster of --jobs workers (at least "
        "2), 'tcp://HOST:PORT' joins a running scheduler (needs the 'dask' extra)",
    )
    p.add_argument(
        "--candidates",
        metavar="K",
        type=int,
        help="check and plan up front only each joint's K nearest pairs, the rest on demand "
        "(for hundreds of joints; default: every pair checked straight)",
    )
    p.add_argument(
        "--candidate-radius",
        metavar="MM",
        type=float,
        help="with --candidates: neighbours farther than this are planned only on demand",
    )
    p.add_argument(
        "--memory-limit",
        metavar="GB",
        type=positive_gb,
        help="refuse up front a run whose estimated peak memory (grid + pair tables) exceeds "
        "this (default: 80 %% of the memory available at start)",
    )
    p.add_argument(
        "--skip-unreachable",
        action="store_true",
        help="plan the largest group of joints that reach each other and list the others, with "
        "the reason, in the summary and the route JSON (stats.skipped); exit code 3",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bars and no summary on stdout")
    from weldplan.commands._robot import add_robot_arguments
    from weldplan.commands._tool import add_tool_arguments

    add_tool_arguments(p)
    add_robot_arguments(p)


def positive_mm(text: str) -> float:
    """argparse type: a positive, finite number of millimetres."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number of mm, got {text!r}")
    return value


def seed_type(text: str) -> int:
    """argparse type: an integer >= 0 (what numpy's ``default_rng`` takes)."""
    from weldplan.errors import ConfigError
    from weldplan.weld.validate import seed

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    try:
        return seed(value)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(exc.message) from None


def positive_gb(text: str) -> float:
    """argparse type: a positive, finite number of GB."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0 < value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number of GB, got {text!r}")
    return value


def _post_names() -> list[str]:
    from weldplan.io.export import POSTS

    return sorted(POSTS)


def config_from_args(args: argparse.Namespace) -> Any:
    from weldplan.weld.pipeline import PlanConfig

    if args.aco < 1:
        raise WeldplanError(f"--aco must be >= 1, got {args.aco}")
    if args.jobs < 1:
        raise WeldplanError(f"--jobs must be >= 1, got {args.jobs}")
    return PlanConfig(
        clearance=getattr(args, "clearance", 5.0),
        pitch=getattr(args, "pitch", 5.0),
        margin=getattr(args, "margin", 150.0),
        planner=args.planner,
        sequencer=args.sequencer,
        aco={"n_iterations": args.aco, "n_ants": args.aco},
        refine=not getattr(args, "no_refine", False),
        smooth=bool(getattr(args, "smooth", False)),
        smooth_spacing=getattr(args, "smooth_spacing", 5.0),
        candidates=getattr(args, "candidates", None),
        candidate_radius=getattr(args, "candidate_radius", None),
        skip_unreachable=bool(getattr(args, "skip_unreachable", False)),
        memory_limit=getattr(args, "memory_limit", None),
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

    out = {"csv": Path(args.output)}
    if args.json:
        out["json"] = Path(args.json)
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
    extra_rows: list[tuple[str, str]] = []
    texts: dict[str, str] = {}
    robot_partial = False
    reach = None
    if robot is not None:  # the robot's reach test for the weld poses (robotpose, #17)
        from weldplan.commands._robot import pose_acceptance

        reach = pose_acceptance(args, cell, route, tool[0], robot)  # type: ignore[index]
    if tool is not None:
        staged = _pose_stage(args, cell, route, tool, bars, times, reach and reach.accept)
        if staged is None:
            return 1
        route, extra_rows = staged
    if robot is not None:
        from weldplan.commands._robot import robot_stage

        with bars.stage("robot") as st:
            stage = robot_stage(args, cell, route, tool[0], robot, outputs, reach)  # type: ignore[index]
        times["robot"] = st.seconds
        extra_rows += stage.rows
        texts = stage.texts
        route = stage.route  # with the robot route, for the JSON
        robot_partial = bool(stage.skipped)

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
    if robot_partial and code == 0:
        from weldplan.errors import EXIT_PARTIAL

        print(f"weldplan: {len(stage.skipped)} weld(s) not in the robot program", file=sys.stderr)
        code = EXIT_PARTIAL
    return code


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
    from weldplan.viz.viewer import static_html

    texts = {"csv": to_csv_text(route)}
    if "json" in outputs:
        texts["json"] = route.to_json() + "\n"
    if "html" in outputs:
        texts["html"] = static_html(route, cell.part, tool=tool)
    if "post" in outputs and "post" not in (staged or {}):
        texts["post"] = render_post(route, args.post, cell)
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


def _gap_rounds(g: Any) -> str:
    """The converging rounds of the lazy costs (:func:`weldplan.weld.converge.close_gap`)."""
    if not g:
        return ""
    return f"; {g['rounds']} gap round(s) planned {g['pairs_planned']} more pair(s) ({g['reason']})"


def _gaps(route: Any) -> str:
    """The gap to the straight-line bound, and to the tighter bounds that the reader can use."""
    if len(route.joint_ids) < 2 or not route.lower_bound > 0:
        return "n/a"
    parts = [
        f"{100 * route.gap:.2f} % over the straight-line bound",
    ]
    b = route.stats.get("bound_virtual")
    if b is not None and b == b and b > 0:
        parts.append(
            f"{100 * (route.inner_length / b - 1):.2f} % between virtual joints over their own "
            f"straight-line bound ({b:.2f} mm)"
        )
    b = route.stats.get("bound_with_approaches")
    if b is not None and b == b and b > 0:
        parts.append(
            f"{100 * (route.length / b - 1):.2f} % over the bound with approaches ({b:.2f} mm)"
        )
    b = route.stats.get("bound_planned")
    if b is not None and b == b and b > 0:
        how = route.stats.get("bound_planned_method", "")
        parts.append(
            f"{100 * (route.length / b - 1):.2f} % over the bound of the planned legs "
            f"({b:.2f} mm, {how})"
        )
    return "; ".join(parts)


def _skipped_rows(route: Any) -> list[tuple[str, str]]:
    """One row per joint left out by ``--skip-unreachable``."""
    skipped = route.stats.get("skipped") or []
    if not skipped:
        return []
    rows = [("skipped", f"{len(skipped)} joint(s), not in the route (exit code 3)")]
    rows += [(f"  {s['id']}", s["reason"]) for s in skipped]
    return rows


def smooth_rows(route: Any) -> list[tuple[str, str]]:
    """The smoothing's totals (``--smooth``), and one row per leg whose polyline was kept."""
    sm = route.stats.get("smooth")
    if not sm:
        return []
    c = sm["clearance"]
    k = sm["max_curvature"]
    line = (
        f"{sm['smoothed']} of {sm['curved']} curved legs smoothed ({len(route.legs)} legs, "
        f"{len(route.legs) - sm['curved']} straight between their virtual joints)"
    )
    if sm["smoothed"]:
        radius = f", radius {1 / k:.2f} mm" if k > 0 else ""
        m = sm["min_clearance_margin"]
        line += (
            f"; max curvature {k:.4f} 1/mm{radius}; min clearance {c + m:.3f}"
            f" mm (margin {m:.3f} mm over {c:g}); smooth length "
            f"{sm['length']:.2f} mm ({sm['length'] - route.length:+.2f}); spacing <= "
            f"{sm['spacing']:g} mm"
        )
    rows = [("smooth", line)]
    rows += [
        (f"  leg {f['leg']}", f"{f['from_id']} -> {f['to_id']}: {f['status']}")
        for f in sm["legs"]
        if f["curved"] and not f["smoothed"]
    ]
    return rows


def summary_table(
    route: Any,
    times: dict[str, float],
    outputs: dict[str, Path],
    *,
    title: str,
    report: Any,
    note: str | None = None,
    extra: list[tuple[str, str]] | None = None,
) -> str:
    """The table printed at the end of a run (``extra``: rows after ``verified``)."""
    s = route.stats
    rows = [
        (
            "joints",
            f"{len(route.joint_ids)}"
            + (
                f" ({len(route.order)} in the route)"
                if len(route.order) < len(route.joint_ids)
                else ""
            ),
        ),
        ("pairs", f"{s['pairs']} ({s['pairs_straight']} straight, {s['pairs_blocked']} blocked)"),
        (
            "pairs planned",
            f"{s['pairs_planned']} of {s['pairs_blocked']} blocked "
            f"({route.settings['planner']}, {s['rounds']} sequencing rounds"
            + (f", {s['pairs_failed']} failed" if s["pairs_failed"] else "")
            + ")",
        ),
        ("sequencer", f"{s['sequence_method']}" + _gap_rounds(s.get("gap_rounds"))),
        (
            "route length",
            f"{route.length:.2f} mm ({route.inner_length:.2f} mm between virtual joints "
            f"+ {route.approach_length:.2f} mm of approaches to the weld spots)",
        ),
        ("lower bound", f"{route.lower_bound:.2f} mm ({route.lower_bound_method})"),
        ("gap", _gaps(route)),
        ("order", "-".join(route.order)),
        *_skipped_rows(route),
        *smooth_rows(route),
        ("verified", report.describe()),
        *(extra or []),
        (
            "time",
            ", ".join(f"{k} {v:.2f} s" for k, v in times.items()),
        ),
        ("written", ", ".join(str(p) for p in outputs.values())),
    ]
    w = max(len(k) for k, _ in rows)
    lines = [title, "-" * len(title)] + [f"{k:<{w}}  {v}" for k, v in rows]
    if note:
        lines.append(note)
    return "\n".join(lines)
