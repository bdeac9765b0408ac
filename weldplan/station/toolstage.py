"""The tool stages of a station: weld poses, then transitions (docs/tool.md).

After the point-tip route has been planned and verified, :func:`poses_stage` plans a pose of
the whole tool at every weld in the route's order (:func:`weldplan.tool.plan_weld_poses`),
accepted by the caller's test (the robot's reach, :mod:`weldplan.robot.placement.posechoice`) and by
the exit test (:class:`weldplan.tool.poses.ExitTest`: the tool can leave the pose), and re-checks
them independently (:func:`weldplan.tool.verify.verify_poses`, fresh FCL models). A weld
without a free pose is listed with its closest miss.

:func:`transitions_stage` orders the welds with a pose on the tool's own costs
(:func:`weldplan.tool.transitions.plan_ordered_transitions`; ``order = "route"`` keeps the point-tip
order): the tool retracts, moves and approaches, every motion checked for the swept tool,
blocked ones re-planned in SE(3) with OMPL; the whole path is re-checked independently
(:func:`weldplan.tool.verify.verify_sweeps`). A blocked transition is listed.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from weldplan.station.model import ToolSettings
from weldplan.tool.section import ToolSection
from weldplan.tool.settings import OrderSettings, PoseSearchSettings, TransitionSettings


@dataclass(frozen=True, eq=False)
class PosesResult:
    """The weld poses (:class:`~weldplan.tool.poses.WeldPoses`), their re-check
    (:class:`~weldplan.tool.verify.PosesVerification`), and the exit test's transition
    planner (its checked exits are reused by the transitions; None without the exit test)."""

    poses: Any
    check: Any
    planner: Any = None


@dataclass(frozen=True, eq=False)
class TransitionsResult:
    """The tool path (:class:`~weldplan.tool.transitions.ToolPath`) and its re-check
    (:class:`~weldplan.tool.verify.SweepsVerification`)."""

    path: Any
    sweeps: Any


@dataclass(frozen=True)
class ToolChecks:
    """The re-checks of the tool stage: poses (``checked`` ok poses) and sweeps."""

    ok: bool
    checked: int
    failures: tuple[tuple[str, str], ...]
    sweeps: Any = None


def pose_settings(settings: ToolSettings) -> PoseSearchSettings:
    """The pose search's settings (:class:`~weldplan.tool.settings.PoseSearchSettings`) of the
    station's tool stage: its cone and contact radius, the rest the search's defaults."""
    return PoseSearchSettings(cone=settings.cone, contact_radius=settings.contact_radius)


def transition_settings(settings: ToolSettings, seed: int | None) -> TransitionSettings:
    """The transition planner's settings (:class:`~weldplan.tool.settings.TransitionSettings`)
    of the station's tool stage, one place for the exit test's planner and the transitions
    stage, which must agree: no SE(3) re-plan at ``se3_time`` 0, and the SE(3) metric's weight
    at least 1 mm per rad."""
    return TransitionSettings(
        retract=settings.retract, side_exit=settings.side_exit, slide=settings.slide,
        se3=settings.se3_time > 0, time_s=max(settings.se3_time, 1e-3), seed=seed,
        rot_weight=max(settings.rot_weight, 1.0),
    )  # fmt: skip


def order_settings(settings: ToolSettings) -> OrderSettings:
    """The weld order's settings (:class:`~weldplan.tool.settings.OrderSettings`) of the
    station's tool stage: its rotation weight, and the point-tip order kept for ``order =
    "route"``."""
    return OrderSettings(rot_weight=settings.rot_weight, keep_order=settings.order == "route")


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
    from weldplan.tool.poses.choice import all_of

    exits = None
    if settings.exit_check:
        from weldplan.tool.poses.exits import ExitTest
        from weldplan.tool.transitions.plan import TransitionPlanner

        planner = TransitionPlanner(
            cell.part, tool, transition_settings(settings, seed),
            clearance=float(cell.clearance), contact_radius=settings.contact_radius,
        )  # fmt: skip
        exits = ExitTest(planner, route.order)
    poses = plan_weld_poses(
        cell, route, tool, pose_settings(settings), accept=all_of(accept, exits)
    )
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
    from weldplan.tool.transitions.reorder import plan_ordered_transitions
    from weldplan.tool.verify.sweeps import verify_sweeps

    path = plan_ordered_transitions(
        part, tool, poses.poses, transition_settings(settings, seed), order_settings(settings),
        reuse=poses.planner,
    )  # fmt: skip
    return TransitionsResult(path, verify_sweeps(path, poses.poses, part, tool))


def with_tool(
    route: Any, provenance: dict[str, Any], poses: PosesResult, path: TransitionsResult | None
) -> Any:
    """``route`` carrying the tool stage's results in ``route.tool`` (what the route JSON and
    the exporters read), written through its typed view
    (:class:`~weldplan.tool.section.ToolSection`)."""
    section = ToolSection(
        provenance=provenance,
        poses=poses.poses,
        transitions=None if path is None else path.path,
    )
    return section.on(route)


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
