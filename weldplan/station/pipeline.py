"""``weldplan.plan(station)``: the whole job, stage by stage, as one library call.

As pymoo's ``minimize`` runs an algorithm's steps in order and attaches the result
(../shared/DESIGN.md), :func:`plan` runs the named stages of a
:class:`~weldplan.station.model.Station` in order and returns a frozen :class:`Plan` holding each
stage's typed result, its stats and its seconds (:class:`StageRecord`):

``cell``
    the part, the welds, the search grid and the virtual joints (:mod:`weldplan.weld.cell`);
``route``
    the local paths and the order (:func:`weldplan.weld.pipeline.plan_route`; one stage because
    the sequencer asks for the blocked pairs it uses, round after round, so the local paths
    and the order are planned together), then its independent re-check
    (:func:`weldplan.weld.verify.verify_route`);
``reach``, ``poses``, ``transitions``
    with a tool (:mod:`weldplan.station.toolstage`; ``reach`` with a robot,
    :mod:`weldplan.station.robotstage`);
``robot``, ``program``
    with a robot: the joint route, then its timing and program
    (:mod:`weldplan.station.robotstage`).

A re-check that fails raises :class:`~weldplan.errors.PlanningError` (nothing is half-planned);
a weld left out (no pose, blocked, not served) is listed in the plan (:meth:`Plan.partial`).
Writing the files is :func:`weldplan.station.outputs.write_plan`'s.

Randomness: ``rng`` (an integer >= 0, a Generator, or None for the station's ``seed``) is
turned into one integer seed once, and every stochastic stage gets that seed: the same station
and seed give the same files.
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from weldplan.errors import PlanningError
from weldplan.station.model import Station

#: what the run says before it starts, and records in the route JSON (``settings["warnings"]``)
SMOOTH_WITH_TOOL_WARNING = (
    "--smooth with --tool/--robot: the tool poses, tool transitions, robot route, robot "
    "program and the 3D pages follow the polyline, not the smooth path; only the route "
    "CSV/JSON (and a post without --robot) carry the smooth waypoints"
)

Progress = Callable[[str, int, int], None]
#: the route stage's own steps, timed in ``route.stats["seconds"]``
ROUTE_STEPS = ("straight", "local", "sequence", "smooth")


@dataclass(frozen=True)
class StageRecord:
    """One stage of a plan: its name, wall seconds and stats (figures, JSON-like)."""

    name: str
    seconds: float
    stats: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, eq=False)
class Plan:
    """What :func:`plan` returns: each stage's result.

    Attributes
    ----------
    station
        The station planned.
    seed
        The integer seed every stage used.
    cell
        The :class:`~weldplan.weld.cell.Cell`.
    route
        The :class:`~weldplan.weld.route.Route`, carrying what the later stages added
        (``route.tool``: poses, transitions, robot route) as the route JSON stores them.
    verification
        The point-tip route's independent re-check
        (:class:`~weldplan.weld.verify.VerifyReport`).
    tool
        The :class:`~weldplan.station.mount.MountedTool` (None without a tool).
    poses, transitions
        :class:`~weldplan.station.toolstage.PosesResult`,
        :class:`~weldplan.station.toolstage.TransitionsResult` (None without a tool).
    robot, program
        :class:`~weldplan.station.robotstage.RobotResult` and the
        :class:`~weldplan.robot.program.ProgramBuild` (None without a robot).
    stages
        The :class:`StageRecord` of each stage run, in order.
    warnings
        What the run warned of (also in ``route.settings["warnings"]``).
    """

    station: Station
    seed: int | None
    cell: Any
    route: Any
    verification: Any
    tool: Any = None
    poses: Any = None
    transitions: Any = None
    robot: Any = None
    program: Any = None
    stages: tuple[StageRecord, ...] = ()
    warnings: tuple[str, ...] = ()

    @property
    def times(self) -> dict[str, float]:
        """Seconds by stage (the route's own: straight, local, sequence, smooth)."""
        out: dict[str, float] = {}
        for s in self.stages:
            if s.name == "route":
                sub = s.stats.get("seconds", {})
                out.update({k: sub[k] for k in ROUTE_STEPS if k in sub})
            else:
                out[s.name] = s.seconds
        return out

    def partial(self) -> list[str]:
        """One line per cause of a partial plan (joints skipped, welds without a pose,
        blocked transitions, welds not in the program); empty when complete."""
        from weldplan.station.summary import partial_lines

        return partial_lines(self)

    def summary(self, title: str = "weldplan plan") -> str:
        """The table ``weldplan plan`` prints at the end of a run (without the files written):
        the route, its verification, the tool and robot stages, the stage times."""
        from weldplan.station.summary import plan_rows, summary_table

        return summary_table(
            self.route, self.times, {}, title=title, report=self.verification,
            extra=plan_rows(self),
        )  # fmt: skip

    @property
    def tool_route(self) -> Any:
        """The route's tool section typed (:class:`~weldplan.robot.program.ToolRoute`:
        weld poses, tool path, robot route; empty without a tool), as the route JSON saves it."""
        from weldplan.robot.program.toolroute import ToolRoute

        return ToolRoute.of(self.route)

    def save(self, path: Any) -> Any:
        """Write the route JSON (and its timings beside it) as one set, whole or not at all
        (:func:`weldplan.station.saved.save_route`); :func:`weldplan.station.saved.load_plan`
        reads it back. Returns the path."""
        from weldplan.station.saved import save_route

        return save_route(self.route, path)

    def verify(self) -> Any:
        """Re-check the plan as it would be saved, independently of the planner
        (:func:`weldplan.station.recheck.recheck`: the part pose, the point-tip route by FCL, the
        weld poses and transitions of the whole tool, the robot route by FK + FCL).

        The route is first written to its JSON text and read back, so what is checked is what
        :meth:`save` writes, re-parsed (none of the planner's objects or caches).

        Returns
        -------
        :class:`~weldplan.station.recheck.Verdict`
        """
        from weldplan.io.timings import route_json_texts
        from weldplan.station.recheck import recheck
        from weldplan.weld.route import Route

        route = Route.from_json(route_json_texts(self.route)[0])
        robot = None if self.robot is None else self.robot.robot
        return recheck(
            route, self.cell.part, tool=self.tool, robot=robot, joints=self.cell.joints,
            part_pose=_pose_check(route, getattr(self.cell, "part_pose", None)),
        )  # fmt: skip


def _pose_check(route: Any, pose: Any) -> Any:
    """The part pose the route records against the cell's (:class:`CheckResult`)."""
    from weldplan.cellframe import PartPose
    from weldplan.station.recheck import CheckResult

    rec = route.provenance.get("part_pose")
    saved = None if rec is None else PartPose.from_dict(rec)
    if saved is None and pose is None:
        return CheckResult("part pose", True, "planned in the part frame")
    ok = saved is not None and pose is not None and saved.same_as(pose)
    said = "none" if saved is None else saved.describe()
    text = said if ok else f"the route records {said}, the cell has {pose and pose.describe()}"
    return CheckResult("part pose", ok, text)


def run_warnings(station: Station) -> list[str]:
    """Settings whose combination does less than a reader expects."""
    if station.route.smooth and station.robots:
        return [SMOOTH_WITH_TOOL_WARNING]
    return []


def draw_seed(rng: Any, default: int) -> int | None:
    """The one integer seed of a run: ``rng`` itself when an integer, one draw from it when a
    Generator, ``default`` when None."""
    from weldplan.weld.validate import seed

    rng = seed(rng)
    if rng is None:
        return default
    if isinstance(rng, int):
        return rng
    return int(np.random.default_rng(rng).integers(2**63))


class _Stages:
    """Times the stages, reports them to ``progress`` and keeps their records."""

    def __init__(self, progress: Progress | None) -> None:
        self.progress = progress
        self.records: list[StageRecord] = []

    @contextlib.contextmanager
    def stage(self, name: str) -> Iterator[dict[str, Any]]:
        stats: dict[str, Any] = {}
        t0 = time.perf_counter()
        if self.progress is not None:
            self.progress(name, 0, 1)
        yield stats
        if self.progress is not None:
            self.progress(name, 1, 1)
        self.records.append(StageRecord(name, time.perf_counter() - t0, stats))


def check_station_size(station: Station, *, cli: bool = False, workers: int | None = None) -> None:
    """Refuse up front a station whose grid or pair work would not fit
    (:func:`weldplan.weld.sizing.check_size`), before the cell is built."""
    from weldplan.weld.sizing import check_size

    xyz = _weld_points(station)
    config = station.plan_config()
    check_size(
        xyz, pitch=config.pitch, margin=config.margin, n_joints=len(xyz),
        candidates=config.candidates, memory_limit=config.memory_limit, cli=cli,
        workers=station.jobs if workers is None else workers,
    )  # fmt: skip


def _weld_points(station: Station) -> Any:
    """The welds' ``(n, 3)`` positions (mm), read cheaply (the cell reads them again and says
    its warnings there, once)."""
    if station.part.is_demo:
        from weldplan.weld import demo_part

        return demo_part.TABLE1_XYZ
    import logging

    from weldplan.io.joints import read_joints

    logger = logging.getLogger("weldplan.io.joints")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        xyz = read_joints(station.part.welds, units=station.part.units).xyz  # type: ignore[arg-type]
        pose = station.part_pose
        return xyz if pose is None else pose.to_cell(xyz)  # the grid's box, less the lift
    finally:
        logger.setLevel(level)


def cell_stage(station: Station) -> Any:
    """The :class:`~weldplan.weld.cell.Cell` of the station's part and welds."""
    from weldplan.weld.cell import demo_cell, load_cell
    from weldplan.weld.cellsettings import CellBuildSettings

    c, p = station.cell, station.part
    if p.is_demo:
        return demo_cell(
            settings=CellBuildSettings(pitch=c.pitch, clearance=station.clearance, margin=c.margin,
                                  spot_depth=c.spot_depth)
        )  # fmt: skip
    settings = CellBuildSettings(
        pitch=c.pitch, clearance=station.clearance, margin=c.margin,
        approach_cone=c.approach_cone, max_joint_distance=c.max_joint_distance,
        spot_depth=c.spot_depth,
    )  # fmt: skip
    return load_cell(
        p.mesh, p.welds, units=p.units, scale=p.scale, length=p.length,  # type: ignore[arg-type]
        part_pose=station.part_pose, settings=settings,
    )  # fmt: skip


def route_stage(
    station: Station, cell: Any, *, seed: int | None, executor: Any, progress: Any, leg_cost: Any
) -> Any:
    """The point-tip route (:func:`weldplan.weld.pipeline.plan_route`); with ``station.jobs``
    > 1 and no ``executor``, on a process pool holding the cell."""
    from weldplan.weld import pipeline

    with contextlib.ExitStack() as stack:
        if executor is None and station.jobs > 1:
            from weldplan.weld.parallel import process_pool

            executor = stack.enter_context(process_pool(cell, station.jobs))
        extra = {} if leg_cost is None else {"leg_cost": leg_cost}
        return pipeline.plan_route(
            cell, config=station.plan_config(), rng=seed, executor=executor, progress=progress,
            **extra,
        )  # fmt: skip


def plan(
    station: Station,
    *,
    rng: Any = None,
    executor: Any = None,
    progress: Progress | None = None,
) -> Plan:
    """Plan ``station``: every stage of the module docstring, in order.

    Parameters
    ----------
    station
        :class:`~weldplan.station.model.Station` (:func:`~weldplan.station.load.load_station`).
    rng
        Integer >= 0, Generator or None (the station's ``seed``): module docstring.
    executor
        Where blocked pairs are planned (any ``concurrent.futures.Executor``; default: a process
        pool of ``station.jobs`` workers, or this process).
    progress
        ``progress(stage, done, total)``: the stages' names and the route's own
        (``"straight"``, ``"local"``, ``"sequence"``).

    Returns
    -------
    Plan
        With several robots a :class:`weldplan.multi.station.StationPlan` instead: the
        weld allocation, then one :class:`Plan` per robot (no robot-robot interference check
        yet).

    Raises
    ------
    PlanningError
        The route or the weld poses fail their independent re-check, the robot serves no weld
        or its path still collides.
    """
    spec = station.robot  # one robot, or none
    seed = draw_seed(rng, station.seed)
    warnings = run_warnings(station)
    mounted, robot = _load_robot(spec)  # a bad tool or robot fails before the (slow) cell
    check_station_size(station)
    st = _Stages(progress)
    with st.stage("cell"):
        cell = cell_stage(station)
    ctx = _RobotContext.of(station, spec, mounted, robot, seed)
    leg_cost = None
    if ctx is not None and ctx.settings.cost == "time":
        with st.stage("cost") as stats:
            legs, ctx = ctx.time_legs(cell)
            leg_cost = legs.cost
    with st.stage("route") as stats:
        route = route_stage(
            station, cell, seed=seed, executor=executor, progress=progress, leg_cost=leg_cost
        )
        stats["seconds"] = dict(route.stats.get("seconds", {}))
    if leg_cost is not None:
        from weldplan.station.robotstage import with_time_stats

        route = with_time_stats(route, legs, tuple(str(i) for i in cell.joints.ids))
    with st.stage("verify"):
        from weldplan.weld.verify import verify_route

        report = verify_route(route, cell.part, joints=cell.joints)
    if not report.ok:
        raise PlanningError(f"{report.describe()}; nothing written")
    base = Plan(station, seed, cell, route, report, tool=mounted)
    out = _tool_robot(base, st, ctx)
    if warnings:
        out = dataclasses.replace(out, route=_with_warnings(out.route, warnings))
    return dataclasses.replace(out, stages=tuple(st.records), warnings=tuple(warnings))


def _load_robot(spec: Any) -> tuple[Any, Any]:
    """``(MountedTool or None, Robot or None)`` of the station's robot entry."""
    if spec is None:
        return None, None
    from weldplan.station.mount import mount_tool

    if spec.urdf is None:
        return mount_tool(spec.tool), None
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import base_pose

    base = None if spec.base is None else base_pose(*spec.base)
    robot = load_robot(spec.urdf, spec.opw, base=base)
    return mount_tool(spec.tool, robot), robot


@dataclass(frozen=True, eq=False)
class _RobotContext:
    """What the robot stages share: the robot (placed, once fixed), its tool, its settings."""

    spec: Any
    mounted: Any
    robot: Any
    settings: Any
    tool: Any
    floor_z: float | None
    seed: int | None
    base_fixed: bool

    @classmethod
    def of(cls, station: Station, spec: Any, mounted: Any, robot: Any, seed: int | None) -> Any:
        if robot is None:
            return None
        fixed = spec.base is not None or spec.settings.cost == "time"
        floor = station.floor_z
        if floor is None and station.part_pose is not None:  # the cell's floor, checked
            floor = station.part_pose.floor_z
        return cls(spec, mounted, robot, spec.settings, station.tool, floor, seed, fixed)

    @property
    def search(self) -> Any:
        return self.spec.base_search(self.floor_z)

    def kw(self) -> dict[str, Any]:
        return {
            "tool": self.tool, "floor_z": self.floor_z, "search": self.search,
            "roadmap": self.settings.roadmap,
        }  # fmt: skip

    def time_legs(self, cell: Any) -> tuple[Any, _RobotContext]:
        """``cost = "time"``: the leg times, and this context with the robot placed."""
        from weldplan.station.robotstage import time_leg_cost

        legs, robot = time_leg_cost(
            cell, self.mounted, self.robot, self.spec.base is not None,
            settings=self.settings, **self.kw(),
        )  # fmt: skip
        return legs, dataclasses.replace(self, robot=robot)


def _tool_robot(p: Plan, st: _Stages, ctx: _RobotContext | None) -> Plan:
    """The tool and robot stages on the verified route ``p.route``."""
    import weldplan.station.robotstage as robotstage
    import weldplan.station.toolstage as toolstage

    if p.tool is None:
        return p
    reach = None
    if ctx is not None:
        with st.stage("reach"):
            reach = robotstage.reach_test(
                p.cell, p.route, ctx.mounted, ctx.robot, base_fixed=ctx.base_fixed, **ctx.kw()
            )
    settings = p.station.tool
    with st.stage("poses") as stats:
        poses = toolstage.poses_stage(
            p.cell, p.route, p.tool.tool, settings, seed=p.seed, accept=reach and reach.accept
        )
        stats.update(ok=poses.poses.n_ok, welds=len(poses.poses.poses))
    if not poses.check.ok:
        fails = "; ".join(f"{i}: {r}" for i, r in poses.check.failures[:5])
        raise PlanningError(f"weld poses failed the independent re-check: {fails}; nothing written")
    with st.stage("transitions") as stats:
        path = toolstage.transitions_stage(p.cell.part, p.tool.tool, poses, settings, seed=p.seed)
        stats.update(blocked=len(path.path.blocked), transitions=len(path.path.transitions))
    check_sweeps(path.sweeps)
    route = toolstage.with_tool(p.route, p.tool.provenance, poses, path)
    p = dataclasses.replace(p, route=route, poses=poses, transitions=path)
    if ctx is None:
        return p
    with st.stage("robot") as stats:
        joint = robotstage.joint_route_stage(
            p.cell, route, ctx.mounted, ctx.robot, base_fixed=ctx.base_fixed, reach=reach,
            settings=ctx.settings, seed=ctx.seed, **ctx.kw(),
        )  # fmt: skip
        stats.update(ok=joint.robot_route.n_ok, flips=len(joint.robot_route.flips))
    with st.stage("program") as stats:
        name = p.station.name or "weldplan_route"
        build = robotstage.program_stage(p.cell, route, ctx.mounted, joint, ctx.settings, name)
        stats.update(cycle_s=build.timing.total)
    route = robotstage.with_robot(route, joint, str(ctx.spec.urdf))
    return dataclasses.replace(p, route=route, robot=joint, program=build)


def check_sweeps(sweeps: Any) -> None:
    """Refuse a tool path whose free transitions failed their independent re-check
    (:class:`~weldplan.tool.verify.SweepsVerification`): nothing is written."""
    if not sweeps.ok:
        raise PlanningError(
            f"the tool path failed its independent re-check: {sweeps.describe(5)}; "
            "nothing written"
        )


def _with_warnings(route: Any, warnings: list[str]) -> Any:
    """``route`` with ``warnings`` added to ``settings["warnings"]`` (a new Route)."""
    settings = dict(route.settings)
    settings["warnings"] = [*settings.get("warnings", []), *warnings]
    return dataclasses.replace(route, settings=settings)
