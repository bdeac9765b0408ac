"""The tool stages of a station: weld poses, then transitions (docs/tool.md).

After the point-tip route has been planned and verified, :func:`poses_stage` plans a pose of
the whole tool at every weld in the route's order (:func:`weldplan.tool.plan_weld_poses`),
accepted by the caller's test (the robot's reach, :mod:`weldplan.robot.posechoice`) and by the
exit test (:class:`weldplan.tool.exits.ExitTest`: the tool can leave the pose), and re-checks
them independently (:func:`weldplan.tool.verify_poses.verify_poses`, fresh FCL models). A weld
without a free pose is listed with its closest miss.

:func:`transitions_stage` orders the welds with a pose on the tool's own costs
(:func:`weldplan.tool.reorder.plan_ordered_transitions`; ``order = "route"`` keeps the point-tip
order): the tool retracts, moves and approaches, every motion checked for the swept tool,
blocked ones re-planned in SE(3) with OMPL; the whole path is re-checked independently
(:func:`weldplan.tool.verify_sweeps.verify_sweeps`). A blocked transition is listed.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from weldplan.station.model import ToolSettings


@dataclass(frozen=True, eq=False)
class PosesResult:
    """The weld poses (:class:`~weldplan.tool.result.WeldPoses`), their re-check
    (:class:`~weldplan.tool.verify_poses.PosesVerification`), and the exit test's transition
    planner (its checked exits are reused by the transitions; None without the exit test)."""

    poses: Any
    check: Any
    planner: Any = None


@dataclass(frozen=True, eq=False)
class TransitionsResult:
    """The tool path (:class:`~weldplan.tool.transit.ToolPath`) and its re-check
    (:class:`~weldplan.tool.verify_sweeps.SweepsVerification`)."""

    path: Any
    sweeps: Any


@dataclass(frozen=True)
class ToolChecks:
    """The re-checks of the tool stage: poses (``checked`` ok poses) and sweeps."""

    ok: bool
    checked: int
    failures: tuple[tuple[str, str], ...]
    sweeps: Any = None


def poses_stage(
    cell: Any,
    route: Any,
    tool: Any,
    settings: ToolSettings,
    *,
    seed: int | None,
    accept: Any = None,
) -> PosesResult:
    """Plan the poses in route order and re-check them (module docstring).

    ``accept(i, T)`` (optional): the caller's acceptance test, run before the exit test (off
    with ``settings.exit_check`` false); the exit test's planner is handed to the transitions.
    """
    from weldplan.tool import plan_weld_poses, verify_poses
    from weldplan.tool.pose_choice import all_of

    exits = None
    if settings.exit_check:
        from weldplan.tool.exits import ExitTest
        from weldplan.tool.transitions import TransitionPlanner

        planner = TransitionPlanner(
            cell.part, tool, clearance=float(cell.clearance),
            contact_radius=settings.contact_radius, **settings.transition_kw(seed),
        )  # fmt: skip
        exits = ExitTest(planner, route.order)
    poses = plan_weld_poses(
        cell, route, tool, cone=settings.cone, contact_radius=settings.contact_radius,
        accept=all_of(accept, exits),
    )  # fmt: skip
    if exits is not None:
        poses = dataclasses.replace(poses, stats={**poses.stats, **exits.stats()})
    check = verify_poses(poses, cell.part, tool)
    return PosesResult(poses, check, None if exits is None else exits.planner)


def transitions_stage(
    part: Any,
    tool: Any,
    poses: PosesResult,
    settings: ToolSettings,
    *,
    seed: int | None,
) -> TransitionsResult:
    """Order the welds on the tool's costs and plan the transitions, re-ordering round blocked
    pairs, then re-check them independently (module docstring)."""
    from weldplan.tool.reorder import plan_ordered_transitions
    from weldplan.tool.verify_sweeps import verify_sweeps

    kw = settings.transition_kw(seed)
    path = plan_ordered_transitions(
        part, tool, poses.poses, rot_weight=settings.rot_weight,
        keep_order=settings.order == "route", reuse=poses.planner,
        **{k: v for k, v in kw.items() if k != "rot_weight"},
    )  # fmt: skip
    return TransitionsResult(path, verify_sweeps(path, poses.poses, part, tool))


def with_tool(
    route: Any, provenance: dict[str, Any], poses: PosesResult, path: TransitionsResult | None
) -> Any:
    """``route`` carrying the tool stage's results in ``route.tool`` (what the route JSON and
    the exporters read)."""
    data: dict[str, Any] = {"provenance": provenance, "poses": poses.poses.to_dict()}
    if path is not None:
        data["transitions"] = path.path.to_dict()
    return dataclasses.replace(route, tool=data)


def tool_checks(poses: PosesResult, path: TransitionsResult | None) -> Any:
    """The re-checks the summary reports: the poses' alone when they failed, else both."""
    if path is None:
        return poses.check
    sweeps = path.sweeps
    return ToolChecks(
        ok=sweeps.ok,
        checked=poses.check.checked,
        failures=tuple((f"transition {k}", r) for k, r in sweeps.failures),
        sweeps=sweeps,
    )
