"""The ``--tool`` options of ``plan``, ``demo``, ``verify`` and ``view``; the pose stage.

With ``--tool`` a planning run, after the point-tip route has been planned and verified, plans a
pose of the whole tool at every weld in the route's order
(:func:`weldplan.tool.poses.plan_weld_poses`), re-checks them independently
(:func:`weldplan.tool.verify_poses.verify_poses`, fresh FCL models) and only then renders the
outputs. A weld without a free pose is listed with its closest miss; the run then exits with
:data:`weldplan.errors.EXIT_PARTIAL`.

Then the transitions (issue 16, items 3 and 4): the welds with a pose are ordered on the tool's
own costs (:func:`weldplan.tool.tool_order.tool_order`, ``--rot-weight``; ``--tool-order route``
keeps the point-tip order), the tool retracts ``--retract`` mm along its axis, moves and
approaches, every motion checked for the swept tool, blocked ones re-planned in SE(3) with OMPL
for up to ``--se3-time`` seconds (:func:`weldplan.tool.transitions.plan_transitions`), and the
whole path is re-checked independently (:func:`weldplan.tool.verify_sweeps.verify_sweeps`)
before anything is written. A blocked transition is listed; the run then exits with
``EXIT_PARTIAL``.
"""

from __future__ import annotations

import argparse
import dataclasses
import logging
import math
from dataclasses import dataclass
from typing import Any

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)


def _degrees(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0.0 <= value <= 90.0):
        raise argparse.ArgumentTypeError(f"must lie in [0, 90] degrees, got {text!r}")
    return value


def _cone(text: str) -> float:
    value = _degrees(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"must lie in (0, 90] degrees, got {text!r}")
    return value


def _nonneg_mm(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (0.0 <= value < math.inf):
        raise argparse.ArgumentTypeError(f"must be a finite number of mm >= 0, got {text!r}")
    return value


def add_tool_arguments(p: argparse.ArgumentParser, *, search: bool = True) -> None:
    """``--tool``, ``--tcp``, ``--tool-units``, ``--tool-mesh`` (and the pose search's options)."""
    p.add_argument(
        "--tool",
        metavar="URDF|MESH",
        help="plan (or check) a collision-free pose of this tool at every weld: a URDF (TCP = "
        "its last fixed joint) or a mesh with --tcp (docs/tool.md)",
    )
    p.add_argument(
        "--tcp",
        metavar="X,Y,Z,RX,RY,RZ",
        help="with a mesh --tool: the TCP in the mesh frame (position in --tool-units, fixed-axis "
        "x-y-z rotations in degrees, +z into the part); with a URDF: the TCP joint or link name",
    )
    p.add_argument(
        "--tool-units",
        choices=("m", "mm"),
        help="unit of the tool mesh (default mm for a mesh, m for a URDF's --tool-mesh)",
    )
    p.add_argument(
        "--tool-mesh",
        metavar="F",
        help="with a URDF --tool: a mesh in its root-link frame instead of the URDF's own",
    )
    p.add_argument(
        "--tip-cone",
        metavar="DEG",
        type=_cone,
        help="with --tool: the tool may touch the part only within this many degrees of its "
        "axis behind the TCP, inside the contact sphere (an arc torch's wire and contact tip: "
        "its nozzle never passes through a sheet near the spot); default: the tool's own (none "
        "for a mesh: the whole sphere, as a spot gun's electrodes close over the sheet)",
    )
    if search:
        p.add_argument(
            "--tool-cone",
            metavar="DEG",
            type=_degrees,
            default=15.0,
            help="largest tilt of the tool off the weld's approach axis, degrees (default 15)",
        )
        p.add_argument(
            "--contact-radius",
            metavar="MM",
            type=_nonneg_mm,
            default=20.0,
            help="the tool may touch the part only inside this sphere about the weld spot, mm "
            "(default 20: the electrode tip)",
        )
        p.add_argument(
            "--tool-csv",
            metavar="F",
            help="with --tool: also write the tool's verified path as CSV (the transitions in "
            "the tool's order, one row per TCP pose with its quaternion: the motion the swept "
            "check proved free; weldplan.tool.path_csv)",
        )
        add_transition_arguments(p)


def _seconds(text: str) -> float:
    return _nonneg_mm(text)  # the same rule: a finite number >= 0


def add_transition_arguments(p: argparse.ArgumentParser) -> None:
    """``--retract``, ``--side-exit``, ``--no-slide``, ``--rot-weight``, ``--tool-order``,
    ``--no-exit-check``, ``--se3-time`` (the transitions)."""
    p.add_argument(
        "--retract",
        metavar="MM",
        type=_nonneg_mm,
        default=50.0,
        help="with --tool: leave and approach each weld along the tool axis over this many mm "
        "(default 50; every motion of the swept tool is checked)",
    )
    p.add_argument(
        "--side-exit",
        metavar="MM",
        type=_nonneg_mm,
        default=250.0,
        help="with --tool: where the axial retract is blocked, try leaving sideways by this many "
        "mm first (a C-gun round a flange; default 250, 0: never)",
    )
    p.add_argument(
        "--no-slide",
        dest="slide",
        action="store_false",
        help="with --tool: never slide between welds (lift 4-20 mm off the sheet, slide, lower: "
        "a C-gun stays straddled over the flange; tried after the axial retract by default)",
    )
    p.add_argument(
        "--rot-weight",
        metavar="MM/RAD",
        type=_nonneg_mm,
        default=200.0,
        help="with --tool: the weld order minimises TCP length + this x orientation change "
        "(default 200 mm per rad)",
    )
    p.add_argument(
        "--tool-order",
        choices=("tool", "route"),
        default="tool",
        help="with --tool: order the welds on the tool's costs (default) or keep the point-tip "
        "route's order",
    )
    p.add_argument(
        "--no-exit-check",
        dest="exit_check",
        action="store_false",
        help="with --tool: choose each weld's pose without asking whether the tool can leave it "
        "(a lift off the sheet, the axial retract or a side exit; on by default, docs/tool.md)",
    )
    p.add_argument(
        "--se3-time",
        metavar="S",
        type=_seconds,
        default=10.0,  # weldplan.tool.transitions.DEFAULT_SE3_TIME (not imported: fcl)
        help="with --tool: the CPU-seconds safety net of re-planning one blocked transition in "
        "SE(3), whose budget is a number of checks; a re-plan stopped at 3x this makes the run "
        "not reproducible (default 10; 0: report blocked transitions without re-planning)",
    )


def tool_from_args(args: argparse.Namespace) -> tuple[Any, dict[str, Any]] | None:
    """The tool and its provenance (:func:`weldplan.tool.load.load_tool`), ``None`` without one."""
    if not getattr(args, "tool", None):
        for opt in ("tcp", "tool_units", "tool_mesh", "tip_cone"):
            if getattr(args, opt, None) is not None:
                raise WeldplanError(f"--{opt.replace('_', '-')} needs --tool")
        return None
    from weldplan.tool.load import load_tool

    tool, prov = load_tool(args.tool, tcp=args.tcp, units=args.tool_units, mesh=args.tool_mesh)
    cone = getattr(args, "tip_cone", None)
    if cone is not None:
        import dataclasses

        tool = dataclasses.replace(tool, tip_cone=float(cone), _cache={})
        prov = {**prov, "tip_cone": float(cone)}
    return tool, prov


def plan_poses(
    args: argparse.Namespace,
    cell: Any,
    route: Any,
    tool: Any,
    prov: dict[str, Any],
    accept: Any = None,
) -> tuple[Any, Any]:
    """The pose stage: plan the poses in route order and re-check them independently.

    ``accept(i, T)`` (optional, :mod:`weldplan.tool.pose_choice`): the caller's acceptance test
    (the robot's reach), run before the exit test (:class:`weldplan.tool.exits.ExitTest`, off
    with ``--no-exit-check``); the exit test's transition planner then plans the transitions,
    reusing the exits it checked.

    Returns
    -------
    route, check
        The route carrying the poses (``route.tool``) and the
        :class:`~weldplan.tool.verify_poses.PosesVerification`; the caller writes nothing when
        ``check.ok`` is false.
    """
    from weldplan.tool import plan_weld_poses, verify_poses
    from weldplan.tool.pose_choice import all_of

    seed = getattr(args, "seed", None)
    exits = None
    if getattr(args, "exit_check", True):
        from weldplan.tool.exits import ExitTest
        from weldplan.tool.transitions import TransitionPlanner

        planner = TransitionPlanner(
            cell.part, tool, clearance=float(cell.clearance), contact_radius=args.contact_radius,
            **transition_settings(args, seed),
        )  # fmt: skip
        exits = ExitTest(planner, route.order)
    poses = plan_weld_poses(
        cell, route, tool, cone=args.tool_cone, contact_radius=args.contact_radius,
        accept=all_of(accept, exits),
    )  # fmt: skip
    if exits is not None:
        poses = dataclasses.replace(poses, stats={**poses.stats, **exits.stats()})
    check = verify_poses(poses, cell.part, tool)
    data: dict[str, Any] = {"provenance": prov, "poses": poses.to_dict()}
    if not check.ok:
        return dataclasses.replace(route, tool=data), check
    path, sweeps = plan_tool_path(
        args, cell.part, tool, poses, seed=seed, reuse=None if exits is None else exits.planner
    )
    data["transitions"] = path.to_dict()
    both = ToolChecks(
        ok=sweeps.ok,
        checked=check.checked,
        failures=tuple((f"transition {k}", r) for k, r in sweeps.failures),
        sweeps=sweeps,
    )
    return dataclasses.replace(route, tool=data), both


@dataclass(frozen=True)
class ToolChecks:
    """The re-checks of the tool stage: poses (``checked`` ok poses) and sweeps."""

    ok: bool
    checked: int
    failures: tuple[tuple[str, str], ...]
    sweeps: Any = None


def transition_settings(args: argparse.Namespace, seed: int | None) -> dict[str, Any]:
    """The transition planner's settings from the options (one place for the exit test's
    planner and :func:`plan_tool_path`, which must agree)."""
    return dict(
        retract=args.retract, se3=args.se3_time > 0, time_s=max(args.se3_time, 1e-3), seed=seed,
        rot_weight=max(args.rot_weight, 1.0), side_exit=args.side_exit,
        slide=getattr(args, "slide", True),
    )  # fmt: skip


def plan_tool_path(
    args: argparse.Namespace,
    part: Any,
    tool: Any,
    poses: Any,
    *,
    seed: int | None = None,
    reuse: Any = None,
) -> tuple[Any, Any]:
    """Order the welds on the tool's costs and plan the transitions, re-ordering round blocked
    pairs (:func:`weldplan.tool.reorder.plan_ordered_transitions`; ``--tool-order route``
    keeps the route's order), then re-check them independently.

    ``reuse``: the exit test's :class:`~weldplan.tool.transitions.TransitionPlanner` (its checked
    exits are kept). Returns the :class:`~weldplan.tool.transit.ToolPath` and its
    :class:`~weldplan.tool.verify_sweeps.SweepsVerification`.
    """
    from weldplan.tool.reorder import plan_ordered_transitions
    from weldplan.tool.verify_sweeps import verify_sweeps

    kw = transition_settings(args, seed)
    path = plan_ordered_transitions(
        part, tool, poses, rot_weight=args.rot_weight,
        keep_order=args.tool_order == "route", reuse=reuse,
        **{k: v for k, v in kw.items() if k != "rot_weight"},
    )  # fmt: skip
    return path, verify_sweeps(path, poses, part, tool)


def transition_rows(route: Any, check: Any) -> list[tuple[str, str]]:
    """Summary rows of the transitions: free / total, re-planned, length and rotation versus the
    point-tip order, and each blocked transition."""
    from weldplan.tool.route_frames import route_tool_path

    path = route_tool_path(route)
    if path is None:
        return []
    sweeps = getattr(check, "sweeps", None)
    n = len(path.transitions)
    est = path.stats.get("point_order")
    rows = [
        (
            "tool transitions",
            f"{n - len(path.blocked)} / {n} free for the swept tool ("
            + ", ".join(f"{k} {v}" for k, v in path.by_via().items() if k != "blocked")
            + f"); retract {path.settings['retract']:g} mm, side exit "
            f"{path.settings.get('side_exit', 0):g} mm"
            + (f"; re-checked: {sweeps.describe()}" if sweeps is not None else ""),
        ),
        (
            "tool path",
            f"{path.length:.1f} mm, orientation change {path.rotation:.1f} deg, order "
            f"{path.stats.get('order_from', '?')}"
            + (
                f" (estimated on direct transitions: point-tip order {est['length']:.1f} mm, "
                f"{est['rotation_deg']:.1f} deg; tool order "
                f"{path.stats['tool_order']['length']:.1f} mm, "
                f"{path.stats['tool_order']['rotation_deg']:.1f} deg)"
                if est
                else ""
            ),
        ),
    ]
    rows += [(f"  {t.from_id}->{t.to_id}", f"blocked; {t.reason}") for t in path.blocked]
    return rows


def transitions_partial(route: Any) -> bool:
    """Whether the route's tool path has blocked transitions (one stderr line if so)."""
    import sys

    d = route.tool.get("transitions") if route.tool else None
    if not d:
        return False
    blocked = [f"{t['from']}->{t['to']}" for t in d["transitions"] if t["status"] == "blocked"]
    if blocked:
        shown = ", ".join(blocked[:10]) + (", ..." if len(blocked) > 10 else "")
        print(
            f"weldplan: {len(blocked)} tool transition(s) blocked for the swept tool ({shown})",
            file=sys.stderr,
        )
    return bool(blocked)


def pose_rows(route: Any, check: Any) -> list[tuple[str, str]]:
    """Summary rows of the pose stage: the tool, welds reached, and each miss."""
    from weldplan.tool.result import WeldPoses

    poses = WeldPoses.from_dict(route.tool["poses"])
    n = len(poses.poses)
    rows = [
        ("tool", f"{poses.tool}, sha256 {route.tool['provenance']['file_sha256'][:12]}"),
        (
            "tool poses",
            f"{poses.n_ok} / {n} welds with a free pose (re-checked: {check.checked} ok poses, "
            f"fresh FCL models); total orientation change {poses.total_rotation:.1f} deg"
            + ("" if poses.n_ok == n else "; exit code 3"),
        ),
    ]
    rows += [
        (f"  weld {p.id}", f"no free pose; {p.miss.describe()}" if p.miss else "no free pose")
        for p in poses.poses
        if not p.ok
    ]
    return rows + transition_rows(route, check)
