"""Several robots, one station: ``weldplan.plan(station)`` with more than one ``[[robot]]``.

:func:`plan_station` runs, in order:

1. the cell (:func:`weldplan.station.pipeline.cell_stage`): the part and every weld, in the
   planning frame (the cell frame when the station has a ``part_pose``);
2. every robot's base (:func:`weldplan.multi.cell.place_robots`): a given one checked against
   the part, a missing one searched in the robot's region, in station order, away from the
   robots already placed;
3. per robot, at its base with its own tool, the feasibility study
   (:func:`weldplan.study.check_spots`: a free gun pose on a usable branch with the links
   clear, else why not) and its leg times between the welds it reaches
   (:func:`weldplan.multi.inputs.study_inputs`: the model, station-branch leg times with the
   approach to each weld's virtual joint at both ends, and their all-branch lower bound);
4. the allocation (:func:`weldplan.multi.allocation_report`: ours, the lower bound, the
   one-robot and nearest-robot baselines) over the model; the bound over pose-free leg
   bounds (:func:`weldplan.multi.bound.tcp_leg_bound`), the one over the study's poses (all
   branches) beside it;
5. per robot with welds, the single-robot pipeline (:func:`weldplan.station.pipeline.plan`) on
   a sub-station: the same station (its part pose kept) with that robot alone at its base and
   the welds file restricted to its share (:func:`weldplan.multi.shares.plan_shares`: in turn,
   or side by side on a process pool or the executor given, the same plans either way).
   Steps 4-5 are repeated (:func:`weldplan.multi.calibrate.allocate_and_plan`, at most
   ``settings.rounds`` times) with the planned legs' timed values in place of their model
   times while the station's timed cycle drops; the best round is kept, and a share planned
   in an earlier round is not planned again.

6. robot-robot interference (issue 30, item 4): the pairs of motions of two robots whose swept
   robots come closer than the station's ``clearance``
   (:func:`weldplan.multi.interference.find_interference`), the interlocks that order each such
   pair under any timing (:func:`weldplan.multi.zones.resolve_zones`), each robot's program
   rebuilt with its interlock signals (:attr:`~weldplan.io.posts.program.RobotProgram.signals`),
   the schedule with the waits, and the independent replay
   (:func:`weldplan.multi.replay.replay_station`). Every robot starts and ends at its home
   (:func:`with_homes`, checked before any study: the homes clearance apart), so a robot whose
   first weld is near another's waits there behind an interlock; a robot with no weld stands at
   its home the whole cycle. Conflicts no interlock can order (a motion of one robot that meets
   every configuration of another, e.g. its column; anything against an idle robot) are
   re-allocated and planned again (:func:`weldplan.multi.passes.plan_and_repair`); those left
   are unordered rather than refused: the plan is returned whole, and its replay says
   ``ok=False`` naming the two robots and rows (the interference line names their welds), so
   that a caller (the CLI: a partial result) reports it instead of losing the plan.

Between steps 3 and 4 the robots' rests are checked against each other
(:mod:`weldplan.multi.conflicts`: every robot at its home and at each weld, the study's
configuration), and the allocation keeps a weld from a robot that would meet another at its
home there and charges pairs of welds of two robots that meet
(:mod:`weldplan.multi.passes`).

The result (:class:`StationPlan`) holds each robot's :class:`~weldplan.station.pipeline.Plan`
(its program carrying its signals), the allocation report, the studies, the schedule with the
waits and the replay's verdict.

Frames: every base, study, leg time and plan is in the planning frame, one for all robots
(:mod:`weldplan.multi.cell`). Every robot needs a ``urdf``; two given bases closer than their
footprints are refused before anything slow is loaded (each a
:class:`~weldplan.errors.ConfigError` naming the key).
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from weldplan.errors import ConfigError
from weldplan.multi.conflicts import ConflictSettings, conflict_table
from weldplan.multi.inputs import StudyInputs, stack_inputs, study_inputs
from weldplan.multi.passes import Context, plan_and_repair, rested
from weldplan.multi.problem import AllocationSettings
from weldplan.multi.result import AllocationReport
from weldplan.multi.schedule import ReplayVerdict, StationSchedule, station_schedule

log = logging.getLogger(__name__)

#: what a station plan built without the interference stage says of it
NO_INTERFERENCE = (
    "robot-robot interference not checked: each robot is planned alone against the part"
)


@dataclass(frozen=True, eq=False)
class StationPlan:
    """What :func:`plan_station` returns.

    Attributes
    ----------
    station
        The station planned.
    seed
        The integer seed every stage used.
    report
        The :class:`~weldplan.multi.result.AllocationReport` (ours, bound, baselines; cycle
        times over the leg-time model, s).
    plans
        Per robot its :class:`~weldplan.station.pipeline.Plan`, ``None`` for a robot with no
        weld.
    studies
        Per robot its :class:`~weldplan.study.FeasibilityStudy` (planning frame).
    interference
        One line: the motion pairs checked, the conflicts, zones and interlocks, the replay's
        smallest distance (:data:`NO_INTERFERENCE` when not checked).
    schedule
        The nominal :class:`~weldplan.multi.schedule.StationSchedule` of the timed programs
        (moves, welds, waits on one clock, under the interlocks), ``None`` before it is built.
    replay
        The independent robot-robot replay's :class:`~weldplan.multi.schedule.ReplayVerdict`,
        ``None`` while interference is not checked.
    stats
        ``{"seconds": {stage: wall s}}``: the cell, each robot's study, the allocation, each
        robot's plan, the interference, the zones, the replay (the allocation and the plans
        summed over the rounds).
    rounds
        The :class:`~weldplan.multi.calibrate.CalibrationRound` of every allocate-plan round
        (the model's and the timed cycle); ``report`` and ``plans`` are the best round's.
    """

    station: Any
    seed: int | None
    report: AllocationReport
    plans: tuple[Any, ...]
    studies: tuple[Any, ...] = ()
    interference: str = NO_INTERFERENCE
    stats: dict[str, Any] = field(default_factory=dict)
    schedule: StationSchedule | None = None
    replay: ReplayVerdict | None = None
    rounds: tuple[Any, ...] = ()

    @property
    def allocation(self) -> Any:
        return self.report.ours

    @property
    def timed_cycles(self) -> tuple[float | None, ...]:
        """s per robot: its timed program's cycle (``None``: no weld)."""
        return tuple(None if p is None else float(p.program.timing.total) for p in self.plans)

    @property
    def cycle_time(self) -> float:
        """s: the station's cycle: the schedule's (the last robot's end, its waits at the
        interlocks counted) when there is one, else the slowest robot's timed cycle."""
        if self.schedule is not None:
            return self.schedule.cycle_time
        return max((c for c in self.timed_cycles if c is not None), default=0.0)

    def summary_rows(self) -> list[tuple[str, str]]:
        """``(label, text)`` rows: per robot its welds, allocated and timed cycle, its waits at
        the interlocks, utilisation; the station's cycle beside the bound and the baselines; the
        interference note; whether a clock stopped a MILP (:meth:`AllocationReport.clock_caps`)."""
        a, top = self.allocation, self.cycle_time
        waits = self.schedule.waiting if self.schedule is not None else (0.0,) * len(a.robots)
        rows = []
        for r, name in enumerate(a.robots):
            c = self.timed_cycles[r]
            welded = len(a.shares[r].order)
            util = c / top if c is not None and top > 0 else 0.0
            timed = (
                "idle"
                if c is None
                else f"timed {c:.2f} s, waits {waits[r]:.2f} s, utilisation {util:.0%}"
            )
            rows.append(
                (
                    f"robot {name}",
                    f"{welded} welds, allocated {a.shares[r].cycle_time:.2f} s; {timed}",
                )
            )
        rows.append(("station cycle", f"{top:.2f} s timed (the last robot, waits included)"))
        if self.rounds:
            said = "; ".join(f"{k + 1}: model {c.model_cycle:.2f} s, timed {c.timed_cycle:.2f} s"
                             for k, c in enumerate(self.rounds))  # fmt: skip
            rows.append(("allocate-plan rounds", said))
        rows += [("allocation", line) for line in self.report.lines()]
        rows.append(("interference", self.interference))
        caps = self.report.clock_caps()
        rows.append(("reproducible", "NOT reproducible: " + "; ".join(caps) if caps else "yes"))
        return rows


def _robots(station: Any) -> list[tuple[Any, Any, Any]]:
    """``(spec, MountedTool, Robot)`` per robot (a searched one at the origin until
    :func:`weldplan.multi.cell.place_robots` places it), refusing a robot without a urdf and
    given bases too close together (:func:`weldplan.multi.cell.check_apart`)."""
    from weldplan.multi.cell import check_apart
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import base_pose
    from weldplan.station.mount import mount_tool

    for k, spec in enumerate(station.robots):  # every refusal before any (slow) load
        if spec.urdf is None:
            raise ConfigError(
                f"{len(station.robots)} robots: robot {k + 1} needs a urdf", field="urdf"
            )
    out = []
    for spec in station.robots:
        base = None if spec.base is None else base_pose(*spec.base)
        robot = load_robot(spec.urdf, spec.opw, base=base)
        out.append((spec, mount_tool(spec.tool, robot), robot))
    check_apart(out, source=station.source)
    return out


def with_homes(station: Any, cell: Any, robots: list[tuple[Any, Any, Any]]) -> Any:
    """The station with every robot's home (:attr:`~weldplan.station.model.RobotSettings.home`,
    deg): the one its file gives, else the conventional one (:func:`home_deg`); each checked at
    the robot's base (:func:`weldplan.robot.route.home.check_home`: its length, the joint
    limits, the robot with its tool clear of the part, the floor and itself), and the robots at
    their homes ``clearance`` apart (:func:`~weldplan.multi.interference.find_interference`).
    Several robots need one each: a program that starts at a weld cannot wait for another robot
    anywhere, nor two robots that stand too close at the cycle's start be ordered
    (docs/station.md). Raises :class:`~weldplan.errors.InputError` naming the file, the line
    and ``robot.home``."""
    from weldplan.multi.cell import planning_floor
    from weldplan.robot.collision.checker import RobotCollision
    from weldplan.robot.route.home import check_home

    specs = []
    for k, (spec, mounted, robot) in enumerate(robots):
        checker = RobotCollision(
            robot, cell.part, mounted.tool, mounted.flange_tcp,
            contact_radius=station.tool.contact_radius, floor_z=planning_floor(station),
        )  # fmt: skip
        try:
            check_home(robot, home_deg(spec), checker)
        except ConfigError as exc:
            raise _home_error(station, k, spec, exc.message) from None
        settings = dataclasses.replace(spec.settings, home=home_deg(spec))
        specs.append(dataclasses.replace(spec, settings=settings))
    _homes_apart(station, [(s, m, r) for s, (_, m, r) in zip(specs, robots, strict=True)])
    return dataclasses.replace(station, robots=tuple(specs))


def _home_error(station: Any, k: int, spec: Any, message: str) -> Exception:
    """The :class:`~weldplan.errors.InputError` of robot ``k``'s home: the file, the line of its
    ``home`` (else of its table) and the field ``robot.home``; a home not given asks for one."""
    from weldplan.errors import InputError
    from weldplan.station.load import key_line

    given = spec.settings.home is not None
    ask = "" if given else " (the conventional home: give robot.home)"
    return InputError(
        f"robot {k + 1}: {message}{ask}", path=station.source,
        line=key_line(station.source, ("robot", k, "home") if given else ("robot", k)),
        field="robot.home",
    )  # fmt: skip


def _homes_apart(station: Any, robots: list[tuple[Any, Any, Any]]) -> None:
    """Refuse two robots that come closer than the station's clearance standing at their homes
    (every link and tool, FCL: the planner's interference check of two rests)."""
    from weldplan.multi.interference import InterferenceSettings, MovingRobot, find_interference

    movers = [
        MovingRobot(f"robot{k + 1}", robot, home_timing(spec, robot), mounted.tool,
                    mounted.flange_tcp)
        for k, (spec, mounted, robot) in enumerate(robots)
    ]  # fmt: skip
    found = find_interference(movers, InterferenceSettings(clearance=station.clearance))
    if found.conflicts:
        c = found.conflicts[0]
        raise _home_error(
            station, c.b, robots[c.b][0],
            f"at its home it comes within {c.distance:.1f} mm of robot {c.a + 1} at its home "
            f"({c.bodies}; clearance {station.clearance:g} mm): give each robot a home clear of "
            "the others",
        )  # fmt: skip


def _study(cell: Any, station: Any, k: int, mounted: Any, robot: Any) -> Any:
    """Robot ``k``'s feasibility study of every weld with its own tool, at its base, in the
    planning frame (the cell's part and welds, the planning frame's floor)."""
    from weldplan.multi.cell import study_settings
    from weldplan.study import StudyRobot, StudyTool, check_spots

    tool = StudyTool(f"tool{k + 1}", mounted.tool, mounted.spec)  # mounted as the robot stage does
    return check_spots(
        cell.part, cell.joints, [tool], [StudyRobot(f"robot{k + 1}", robot)],
        study_settings(station), frame=cell.frame,
    )  # fmt: skip


def plan_station(
    station: Any,
    *,
    seed: int | None,
    executor: Any = None,
    progress: Callable[[str, int, int], None] | None = None,
    settings: AllocationSettings | None = None,
) -> StationPlan:
    """Plan a station of several robots (module docstring); ``seed`` as
    :func:`weldplan.station.pipeline.plan` draws it."""
    from weldplan.multi.cell import place_robots
    from weldplan.station.pipeline import cell_stage

    say = progress or (lambda stage, done, total: None)
    seconds: dict[str, float] = {}
    robots = _robots(station)
    if station.part.is_demo:
        station = _demo_files(station)
    t = time.perf_counter()
    cell = cell_stage(station)
    seconds["cell"] = time.perf_counter() - t
    layout = place_robots(cell, station, robots, seconds)
    robots = list(layout.robots)
    # from here on the station holds every robot at its base, the searched ones included: the
    # interference stage, the replay and the saved station read it
    station = dataclasses.replace(station, robots=tuple(spec for spec, _, _ in robots))
    station = with_homes(station, cell, robots)
    robots = [(spec, m, r) for spec, (_, m, r) in zip(station.robots, robots, strict=True)]
    studies, inputs = [], []
    lift = cell.virtual_xyz - np.asarray(cell.joints.xyz)  # each weld to its virtual joint, mm
    for k, (spec, mounted, robot) in enumerate(robots):
        say("study", k, len(robots))
        t = time.perf_counter()
        study = layout.studies[k] or _study(cell, station, k, mounted, robot)
        studies.append(study)
        inputs.append(study_inputs(study, [robot], [spec.settings.weld_time], lift=lift))
        seconds[f"study robot{k + 1}"] = time.perf_counter() - t
    say("study", len(robots), len(robots))
    inp: StudyInputs = stack_inputs(inputs, [f"robot{k + 1}" for k in range(len(robots))])
    t = time.perf_counter()
    homes = [home_deg(spec) for spec, _, _ in robots]
    table = conflict_table(rested(robots, studies, homes),
                           ConflictSettings(clearance=station.clearance))  # fmt: skip
    seconds["conflicts"] = time.perf_counter() - t
    ctx = Context(station, robots, inp, seed, settings or AllocationSettings(), executor,
                  progress, seconds, table, interfere)  # fmt: skip
    got = plan_and_repair(ctx)
    return StationPlan(
        station, seed, got.report, tuple(got.plans), tuple(studies), interference=got.line,
        stats={"seconds": seconds, "cpu": ctx.cpu, "shares": ", ".join(dict.fromkeys(ctx.ran)),
               "conflicts": got.conflicts},
        schedule=got.schedule, replay=got.replay, rounds=got.rounds,
    )  # fmt: skip


def _interference(
    station: Any, plans: list[Any], names: tuple[str, ...], seconds: dict[str, float]
) -> tuple[list[Any], StationSchedule, ReplayVerdict, str]:
    """:func:`interfere` without the conflicts left."""
    return interfere(station, plans, names, seconds)[:4]


def interfere(
    station: Any, plans: list[Any], names: tuple[str, ...], seconds: dict[str, float]
) -> tuple[list[Any], StationSchedule, ReplayVerdict, str, list[tuple[int, str, int, str]]]:
    """Step 6 of the module docstring: ``(plans with their signals, schedule with the waits,
    replay verdict, the interference line, the conflicts no interlock orders as (robot, weld,
    robot, weld): :func:`weldplan.multi.conflicts.blamed`)``."""
    from weldplan.multi.conflicts import blamed
    from weldplan.multi.interference import InterferenceSettings, MovingRobot, find_interference
    from weldplan.multi.replay import replay_station
    from weldplan.multi.zones import resolve_zones

    idle = _idle_at_home(station, plans)
    movers = [
        (MovingRobot(names[k], *idle[k]) if k in idle else None) if p is None else MovingRobot(
            names[k], p.robot.robot, p.program.timing, p.tool.tool if p.tool else None,
            p.tool.flange_tcp if p.tool else None,
        )
        for k, p in enumerate(plans)
    ]  # fmt: skip
    t = time.perf_counter()
    found = find_interference(movers, InterferenceSettings(clearance=station.clearance))
    seconds["interference"] = seconds.get("interference", 0.0) + time.perf_counter() - t
    t = time.perf_counter()
    zones = resolve_zones(found, strict=False)
    seconds["zones"] = seconds.get("zones", 0.0) + time.perf_counter() - t
    ids = [None if p is None else p.program.weld_ids_by_row() for p in plans]
    left = blamed(zones.unresolved, found.motions, ids)
    plans = with_signals(plans, zones.interlocks, names)
    timings = [None if p is None else p.program.timing for p in plans]
    schedule = station_schedule(
        names, timings, zones.interlocks,
        weld_ids=[None if p is None else p.program.weld_ids_by_row() for p in plans],
    )  # fmt: skip
    t = time.perf_counter()
    verdict = replay_station(_replay_robots(station, plans, names, idle), zones.interlocks,
                             station.clearance)  # fmt: skip
    seconds["replay"] = seconds.get("replay", 0.0) + time.perf_counter() - t
    md = "no pair may overlap" if np.isinf(verdict.min_distance) else (
        f"min distance {verdict.min_distance:.1f} mm")  # fmt: skip
    if verdict.ok:
        said = f"replay ok over {verdict.pairs} pairs, {md}"
    else:
        said = f"REPLAY FAILED over {verdict.pairs} pairs: {verdict.failures[0]}"
        log.warning("station: %s", said)
    return plans, schedule, verdict, f"{found.line()}; {zones.line()}; {said}", left


def with_signals(plans: list[Any], interlocks: Sequence[Any], names: Sequence[str]) -> list[Any]:
    """Each plan with its program carrying its interlock signals, in program order (at one
    row: the signal it sets before the one it waits for), each naming the other robot
    (``names``: station order). The one mapping from interlocks to program signals: the
    station's files write the programs as the plan holds them (:mod:`weldplan.multi.saved`)."""
    rows = [None if p is None else p.program.row for p in plans]
    acts: dict[int, list[Any]] = {}
    for lock in interlocks:
        (a, set_), (b, wait) = lock.actions(rows)
        acts.setdefault(a, []).append(dataclasses.replace(set_, peer=names[b]))
        acts.setdefault(b, []).append(dataclasses.replace(wait, peer=names[a]))
    out = list(plans)
    for k, got in acts.items():
        build = plans[k].program
        got.sort(key=lambda s: (s.row, s.action != "set", s.signal))
        program = dataclasses.replace(build.program, signals=tuple(got))
        out[k] = dataclasses.replace(plans[k], program=dataclasses.replace(build, program=program))
    return out


def _idle_at_home(station: Any, plans: list[Any]) -> dict[int, tuple[Any, Any, Any, Any]]:
    """Per robot with no weld, ``(robot at its base, timing at home, tool mesh, flange_tcp)``:
    it stands at its home the whole cycle (:func:`home_timing`), in the interference check
    and the replay like any robot."""
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import base_pose
    from weldplan.station.mount import mount_tool

    out = {}
    for k, (spec, p) in enumerate(zip(station.robots, plans, strict=True)):
        if p is None and spec.urdf is not None and spec.base is not None:
            robot = load_robot(spec.urdf, spec.opw, base=base_pose(*spec.base))
            mounted = mount_tool(spec.tool, robot)
            out[k] = (robot, home_timing(spec, robot), mounted.tool, mounted.flange_tcp)
    return out


def home_deg(spec: Any) -> tuple[float, ...]:
    """deg: robot ``spec``'s home in a station of several robots: its ``home``, else the
    conventional one (:func:`with_homes` checked it at its base)."""
    from weldplan.robot.route.home import CONVENTIONAL_HOME_DEG

    return tuple(spec.settings.home or CONVENTIONAL_HOME_DEG)


def home_timing(spec: Any, robot: Any) -> Any:
    """The :class:`~weldplan.robot.program.TimedTrajectory` of a robot that stands at its home
    (:func:`home_deg`) the whole cycle: one row, one rest. The live plan and ``weldplan
    verify`` (:mod:`weldplan.multi.recheck`) build an idle robot here."""
    from weldplan.robot.program.timing import time_route

    q = np.radians(np.asarray(home_deg(spec), dtype=np.float64))[None]
    return time_route(
        q, robot.velocity, robot.acceleration, weld_rows=[], joint_names=robot.joint_names
    )


def _replay_robots(
    station: Any, plans: list[Any], names: tuple[str, ...], idle: dict[int, Any] | None = None
) -> list[Any]:
    """The robots as the replay reads them: the station's URDF and base, the tool's mesh; an
    idle robot at its home (``idle``: :func:`_idle_at_home`; default: built here)."""
    idle = _idle_at_home(station, plans) if idle is None else idle
    out = []
    for k, (spec, p) in enumerate(zip(station.robots, plans, strict=True)):
        if p is not None:
            out.append(replay_robot(names[k], spec, p.program.timing, p.tool))
        elif k in idle:
            _, timing, tool, flange_tcp = idle[k]
            at_home = SimpleNamespace(tool=tool, flange_tcp=flange_tcp)
            out.append(replay_robot(names[k], spec, timing, at_home if tool is not None else None))
        else:
            out.append(replay_robot(names[k], spec, None, None))
    return out


def replay_robot(name: str, spec: Any, timing: Any, tool: Any) -> Any:
    """One robot as the replay reads it (:class:`~weldplan.multi.replay.ReplayRobot`): the
    URDF and base (x, y, z mm, yaw deg) of its :class:`~weldplan.station.model.RobotSpec`
    ``spec``, its ``timing`` (``None``: idle) and its mounted tool (``.tool`` the mesh in the TCP
    frame, ``.flange_tcp``; ``None``: links only). The live plan and ``weldplan verify`` of a
    saved station (:mod:`weldplan.multi.recheck`) both build it here."""
    from weldplan.multi.replay import ReplayRobot
    from weldplan.robot.placement.reach import base_pose

    mesh = None if timing is None or tool is None else tool.tool
    return ReplayRobot(
        name, Path(spec.urdf), base_pose(*spec.base), timing,
        None if mesh is None else np.asarray(mesh.vertices),
        None if mesh is None else np.asarray(mesh.faces),
        None if mesh is None else tool.flange_tcp,
    )  # fmt: skip


def _demo_files(station: Any) -> Any:
    """The demo station with its part and welds as files (the sub-stations need a file)."""
    from weldplan.weld import demo_part

    if not (demo_part.DEMO_PART.exists() and demo_part.DEMO_JOINTS.exists()):
        raise ConfigError("several robots on the demo need assets/demo installed", field="part")
    part = dataclasses.replace(station.part, mesh=demo_part.DEMO_PART, welds=demo_part.DEMO_JOINTS)
    return dataclasses.replace(station, part=part)
