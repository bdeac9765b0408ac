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
   (:func:`weldplan.multi.inputs.study_inputs`);
4. the allocation (:func:`weldplan.multi.allocation_report`: ours, the lower bound, the
   one-robot and nearest-robot baselines) over the station-branch leg times, the bound over
   the all-branch ones;
5. per robot with welds, the single-robot pipeline (:func:`weldplan.station.pipeline.plan`) on
   a sub-station: the same station (its part pose kept) with that robot alone at its base and
   the welds file restricted to its share (:func:`weldplan.multi.shares.plan_shares`: in turn,
   or side by side on a process pool or the executor given, the same plans either way).

6. robot-robot interference (issue 30, item 4): the pairs of motions of two robots whose swept
   robots come closer than the station's ``clearance``
   (:func:`weldplan.multi.interference.find_interference`), the interlocks that order each such
   pair under any timing (:func:`weldplan.multi.zones.resolve_zones`), each robot's program
   rebuilt with its interlock signals (:attr:`~weldplan.io.posts.program.RobotProgram.signals`),
   the schedule with the waits, and the independent replay
   (:func:`weldplan.multi.replay.replay_station`). Conflicts no interlock can order (two robots
   whose first rows, where each program starts, or last rows are closer than the clearance) are
   left unordered rather than refused: the plan is returned whole, and its replay says
   ``ok=False`` naming the two robots and rows (the interference line too), so that a caller
   (the CLI: a partial result) reports it instead of losing the plan.

The result (:class:`StationPlan`) holds each robot's :class:`~weldplan.station.pipeline.Plan`
(its program carrying its signals), the allocation report, the studies, the schedule with the
waits and the replay's verdict. An idle robot (no weld) is left out of the interference check:
where it stands is not planned.

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
from typing import Any

import numpy as np

from weldplan.errors import ConfigError
from weldplan.multi.inputs import StudyInputs, stack_inputs, study_inputs
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
        robot's plan, the interference, the zones, the replay.
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
    check_apart(out)
    return out


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
    from weldplan.multi.baselines import allocation_report
    from weldplan.multi.cell import place_robots
    from weldplan.multi.shares import plan_shares
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
    studies, inputs = [], []
    for k, (spec, mounted, robot) in enumerate(robots):
        say("study", k, len(robots))
        t = time.perf_counter()
        study = layout.studies[k] or _study(cell, station, k, mounted, robot)
        studies.append(study)
        inputs.append(study_inputs(study, [robot], [spec.settings.weld_time]))
        seconds[f"study robot{k + 1}"] = time.perf_counter() - t
    say("study", len(robots), len(robots))
    inp: StudyInputs = stack_inputs(inputs, [f"robot{k + 1}" for k in range(len(robots))])
    t = time.perf_counter()
    report = allocation_report(
        inp.reach, inp.weld_time, inp.cost, rng=seed, settings=settings, bound_travel=inp.bound
    )
    seconds["allocation"] = time.perf_counter() - t
    shares = plan_shares(station, report.ours, seed=seed, executor=executor, progress=progress)
    seconds.update(shares.seconds)
    plans = list(shares.plans)
    names = report.ours.robots
    plans, schedule, replay, line = _interference(station, plans, names, seconds)
    return StationPlan(
        station, seed, report, tuple(plans), tuple(studies), interference=line,
        stats={"seconds": seconds, "cpu": shares.cpu, "shares": shares.ran},
        schedule=schedule, replay=replay,
    )  # fmt: skip


def _interference(
    station: Any, plans: list[Any], names: tuple[str, ...], seconds: dict[str, float]
) -> tuple[list[Any], StationSchedule, ReplayVerdict, str]:
    """Step 5 of the module docstring: ``(plans with their signals, schedule with the waits,
    replay verdict, the interference line)``."""
    from weldplan.multi.interference import InterferenceSettings, MovingRobot, find_interference
    from weldplan.multi.replay import replay_station
    from weldplan.multi.zones import resolve_zones

    movers = [
        None if p is None else MovingRobot(
            names[k], p.robot.robot, p.program.timing, p.tool.tool if p.tool else None,
            p.tool.flange_tcp if p.tool else None,
        )
        for k, p in enumerate(plans)
    ]  # fmt: skip
    t = time.perf_counter()
    found = find_interference(movers, InterferenceSettings(clearance=station.clearance))
    seconds["interference"] = time.perf_counter() - t
    t = time.perf_counter()
    zones = resolve_zones(found, strict=False)
    seconds["zones"] = time.perf_counter() - t
    plans = with_signals(plans, zones.interlocks, names)
    timings = [None if p is None else p.program.timing for p in plans]
    schedule = station_schedule(
        names, timings, zones.interlocks,
        weld_ids=[None if p is None else timed_weld_ids(p.program) for p in plans],
    )  # fmt: skip
    t = time.perf_counter()
    verdict = replay_station(_replay_robots(station, plans, names), zones.interlocks,
                             station.clearance)  # fmt: skip
    seconds["replay"] = time.perf_counter() - t
    md = "no pair may overlap" if np.isinf(verdict.min_distance) else (
        f"min distance {verdict.min_distance:.1f} mm")  # fmt: skip
    if verdict.ok:
        said = f"replay ok over {verdict.pairs} pairs, {md}"
    else:
        said = f"REPLAY FAILED over {verdict.pairs} pairs: {verdict.failures[0]}"
        log.warning("station: %s", said)
    return plans, schedule, verdict, f"{found.line()}; {zones.line()}; {said}"


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


def _replay_robots(station: Any, plans: list[Any], names: tuple[str, ...]) -> list[Any]:
    """The robots as the replay reads them: the station's URDF and base, the tool's mesh."""
    return [
        replay_robot(names[k], spec, None if p is None else p.program.timing,
                     None if p is None else p.tool)
        for k, (spec, p) in enumerate(zip(station.robots, plans, strict=True))
    ]  # fmt: skip


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


def timed_weld_ids(build: Any) -> dict[int, str]:
    """``{timed row: weld id}`` of a :class:`~weldplan.robot.program.ProgramBuild`: its
    program's weld targets named by the timed rows (:attr:`ProgramBuild.row`) they stand on."""
    by_route = {t.row: t.joint_id for t in build.program.targets if t.kind == "weld"}
    rows = build.row if build.row is not None else range(len(build.timing.row_times))
    return {i: by_route[int(r)] for i, r in enumerate(rows) if int(r) in by_route}


def _demo_files(station: Any) -> Any:
    """The demo station with its part and welds as files (the sub-stations need a file)."""
    from weldplan.weld import demo_part

    if not (demo_part.DEMO_PART.exists() and demo_part.DEMO_JOINTS.exists()):
        raise ConfigError("several robots on the demo need assets/demo installed", field="part")
    part = dataclasses.replace(station.part, mesh=demo_part.DEMO_PART, welds=demo_part.DEMO_JOINTS)
    return dataclasses.replace(station, part=part)
