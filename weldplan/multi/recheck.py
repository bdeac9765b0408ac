"""Re-check a saved station plan whole: what ``weldplan verify STATION_JSON`` runs.

:func:`verify_station` runs, in order, checks that share none of the planner's objects (each
reads the files back):

``allocation``
    every weld of the station's welds file is either in exactly one robot's share or listed
    as unreached (with its reasons); the shares are disjoint and each robot's route JSON
    visits exactly its share. Unreached welds are *left out* (exit 3), not a failure.
``robot<k>``
    each robot's route JSON through the single-robot re-check
    (:meth:`weldplan.station.saved.SavedPlan.verify`: the route by FCL, the gun's poses and
    transitions, the robot route by FK + FCL) with the station's part, tool and robot.
``robot<k> signals``
    each robot's program as written (with ``--post``), parsed back: exactly its side of the
    schedule's interlocks, after the right targets (:mod:`weldplan.multi.programcheck`).
``schedule``
    the station's schedule against the saved trajectories: per robot its moves and welds
    (the waits taken out) last as long as its trajectory CSV, its welds are its route's, its
    activities follow each other without gap or overlap from 0; every interlock holds (the
    waiting robot leaves its row no earlier than the releasing robot is at rest, its weld
    done, at its own); the recorded cycle is the last robot's end.
``interference``
    the independent replay (:func:`weldplan.multi.replay.replay_station`: its own URDF
    reading, FK and FCL) run again from the files: per robot the station file's URDF, base
    and tool (:func:`weldplan.multi.station.replay_robot`, as the live plan builds it), its
    samples from its trajectory CSV, its stop rows and their arrivals from the schedule (each
    arrival on a sample of the CSV within :data:`CYCLE_TOL`), the schedule's interlocks and the
    station's ``clearance``. It passes when the re-run agrees with the recorded replay (the
    same verdict, clearance and pairs of motions that may overlap, the minimum distance within
    :data:`DISTANCE_TOL`); agreeing on robots too
    close, the plan is partial (exit 3) and the pair is named (:func:`too_close_line`: the two
    robots, where each was, the distance against the clearance). A plan that records no replay
    (``null``) is re-run all the same, with nothing to agree with.

A check that fails does not stop the later ones (each reads its own files); the verdict is a
:class:`~weldplan.station.recheck.Verdict` (exit 0 ok, 1 a check failed, 3 ok but welds left
out, or robots too close as recorded: the pair's line is then in the ``interference`` check's
``left_out``, which ``weldplan verify`` says apart from the welds).
"""

from __future__ import annotations

import dataclasses
import re
from collections import Counter
from typing import Any

import numpy as np

from weldplan.errors import InputError, PlanningError
from weldplan.multi.filetiming import (  # noqa: F401 - their users import them from here too
    CYCLE_TOL,
    FileTiming,
    _trajectory_end,
    _trajectory_rows,
    file_timing,
)
from weldplan.station.recheck import CheckResult, Verdict

#: mm: the re-run replay's minimum robot-robot distance against the recorded one
DISTANCE_TOL = 1e-3


def verify_station(saved: Any, *, station: Any = None) -> Verdict:
    """Re-check ``saved`` (:class:`~weldplan.multi.saved.SavedStationPlan`; module docstring).

    ``station``: the :class:`~weldplan.station.model.Station` (default: the station file the
    plan records, read again). Raises :class:`~weldplan.errors.InputError` when there is none,
    or when it does not have the plan's robots."""
    station = station if station is not None else _station(saved)
    if len(station.robots) != len(saved.robots):
        raise InputError(
            f"the station has {len(station.robots)} robots, the plan {len(saved.robots)}",
            path=saved.path, field="robots",
        )  # fmt: skip
    checks = [allocation_check(saved, _weld_ids(station))]
    rounds = rounds_check(saved)
    if rounds is not None:
        checks.append(rounds)
    routes = []
    for k in range(len(saved.robots)):
        check, route = robot_check(saved, station, k)
        if check is not None:
            checks.append(check)
        routes.append(route)
    checks += signal_checks(saved)
    checks.append(schedule_check(saved, routes))
    checks.append(interference_check(saved, station))
    return Verdict(tuple(checks))


def signal_checks(saved: Any) -> list[CheckResult]:
    """Per robot with a program, its interlock signals parsed back against the schedule
    (:func:`weldplan.multi.programcheck.signals_check`)."""
    from weldplan.multi.programcheck import signals_check

    checks = (signals_check(saved, k) for k in range(len(saved.robots)))
    return [c for c in checks if c is not None]


def _station(saved: Any) -> Any:
    return saved.load_station()


def _weld_ids(station: Any) -> list[str]:
    from weldplan.io.joints import read_joints

    p = station.part
    if p.is_demo:
        from weldplan.weld import demo_part

        return list(read_joints(demo_part.DEMO_JOINTS).ids)
    return list(read_joints(p.welds, units=p.units).ids)


def allocation_check(saved: Any, ids: list[str]) -> CheckResult:
    """Every weld of ``ids`` (the welds file) in exactly one share or unreached; the robots'
    recorded shares are the allocation's."""
    a = saved.report.ours
    problems = []
    if Counter(a.welds) != Counter(ids):
        extra, missing = set(a.welds) - set(ids), set(ids) - set(a.welds)
        problems.append(f"welds not the file's (extra {sorted(extra)}, missing {sorted(missing)})")
    held = Counter(a.welds[i] for s in a.shares for i in s.order)
    unreached = {u.weld for u in a.unreached}
    for i, w in enumerate(a.welds):
        r = a.assignment[i] if i < len(a.assignment) else -1
        in_share = r >= 0 and i in a.shares[r].order
        if held[w] + (w in unreached) != 1 or (r >= 0) != in_share:
            problems.append(f"weld {w}: in {held[w]} share(s), unreached {w in unreached}")
    for k, robot in enumerate(saved.robots):
        if k >= len(a.shares) or robot.welds != a.welds_of(k):
            problems.append(f"{robot.name}: its welds are not its share")
    if problems:
        return CheckResult("allocation", False, "; ".join(problems[:3]))
    n = sum(len(s.order) for s in a.shares)
    text = (
        f"{n} of {len(ids)} welds in exactly one robot's share, {len(unreached)} unreached "
        f"(each with its reasons); {len(a.shares)} shares disjoint"
    )
    return CheckResult("allocation", True, text, left_out=tuple(sorted(unreached)))


#: s: a round's recorded cycles and the robots' recorded timed cycles agree to this
ROUND_TOL_S = 1e-6


def rounds_check(saved: Any) -> CheckResult | None:
    """The allocate-plan rounds as recorded (``None``: a file without them): every round
    times every robot and its timed cycle is its slowest robot's, it names robots of the
    station, and the kept round (the least timed cycle, :attr:`~weldplan.multi.saved.
    SavedStationPlan.kept_round`) timed each robot as the robot's recorded program."""
    rounds = tuple(getattr(saved, "rounds", ()) or ())
    if not rounds:
        return None
    R = len(saved.robots)
    problems = []
    for k, c in enumerate(rounds):
        if len(c.timed) != R or any(not 0 <= i < R for i in c.planned):
            problems.append(f"round {k + 1} is not over the station's {R} robots")
        elif abs(max(c.timed, default=0.0) - c.timed_cycle) > ROUND_TOL_S:
            problems.append(f"round {k + 1}: timed cycle {c.timed_cycle:.6f} s is not its "
                            f"slowest robot's {max(c.timed):.6f} s")  # fmt: skip
    kept = saved.kept_round
    if not problems:
        for r, robot in enumerate(saved.robots):
            have = 0.0 if robot.timed_cycle is None else robot.timed_cycle
            got = rounds[kept].timed[r]
            if abs(got - have) > ROUND_TOL_S:
                problems.append(f"{robot.name}: round {kept + 1} timed it {got:.3f} s, its "
                                f"program {have:.3f} s")  # fmt: skip
    if problems:
        return CheckResult("rounds", False, "; ".join(problems[:3]))
    text = (
        f"{len(rounds)} allocate-plan round(s); round {kept + 1} kept, its timed cycle "
        f"{rounds[kept].timed_cycle:.2f} s the robots' programs'"
    )
    return CheckResult("rounds", True, text)


def robot_check(saved: Any, station: Any, k: int) -> tuple[CheckResult | None, Any]:
    """Robot ``k``'s route JSON re-checked alone (module docstring); ``(None, None)`` for an
    idle robot. Returns the check and the :class:`~weldplan.station.saved.SavedPlan`."""
    from weldplan.robot import load_robot
    from weldplan.station.mount import mount_tool
    from weldplan.station.recheck import RobotFiles
    from weldplan.station.saved import PartFiles, load_plan

    robot, spec = saved.robots[k], station.robots[k]
    name = robot.name
    if robot.route is None:
        ok = not robot.welds
        return (None if ok else CheckResult(name, False, "welds but no route JSON")), None
    p = station.part
    mesh = _mesh(station)
    sp = load_plan(robot.route, mesh=mesh, part=PartFiles(p.units, p.scale, p.length))
    if set(sp.route.joint_ids) != set(robot.welds):
        return CheckResult(name, False, f"{robot.route.name} does not visit its share"), sp
    arm = load_robot(spec.urdf, spec.opw)
    v = sp.verify(tool=mount_tool(spec.tool, arm), robot=RobotFiles(spec.urdf, spec.opw))
    text = f"{robot.route.name}: {v.describe()}"
    return CheckResult(name, v.ok, text, left_out=v.left_out), sp


def _mesh(station: Any) -> Any:
    if station.part.is_demo:
        from weldplan.weld import demo_part

        return demo_part.DEMO_PART
    return station.part.mesh


def schedule_check(saved: Any, routes: list[Any]) -> CheckResult:
    """The schedule against each robot's trajectory, route and the interlocks (module
    docstring)."""
    s = saved.schedule
    if s is None:
        return CheckResult("schedule", False, "the plan records no schedule")
    problems = []
    for k, robot in enumerate(saved.robots):
        problems += _robot_schedule(s, k, robot, routes[k])
    problems += [_interlock_problem(s, lock) for lock in s.interlocks]
    if abs(s.cycle_time - saved.cycle_time) > CYCLE_TOL:
        problems.append(f"cycle {saved.cycle_time:.4f} s recorded, {s.cycle_time:.4f} s by it")
    problems = [p for p in problems if p]
    if problems:
        return CheckResult("schedule", False, "; ".join(problems[:3]))
    text = (
        f"{len(saved.robots)} robots' moves and welds match their trajectories within "
        f"{CYCLE_TOL:g} s; {len(s.interlocks)} interlock(s) hold; station cycle "
        f"{s.cycle_time:.2f} s"
    )
    return CheckResult("schedule", True, text)


def _robot_schedule(s: Any, k: int, robot: Any, route: Any) -> list[str]:
    acts = s.of(k)
    if robot.trajectory is None:
        return [f"{robot.name}: activities but no trajectory"] if acts else []
    busy = s.seconds(k, "move") + s.seconds(k, "weld")
    end = _trajectory_end(robot.trajectory)
    out = []
    if abs(busy - end) > CYCLE_TOL:
        out.append(f"{robot.name}: moves and welds {busy:.4f} s, trajectory {end:.4f} s")
    t = 0.0
    for a in acts:
        if abs(a.start - t) > 1e-6:
            out.append(f"{robot.name}: a gap or an overlap at {a.start:.4f} s")
            break
        t = a.end
    welded = {a.label for a in acts if a.kind == "weld"}
    rr = None if route is None else route.robot_route
    if rr is not None and not welded <= set(rr.weld_ids):
        out.append(f"{robot.name}: welds {sorted(welded - set(rr.weld_ids))} not in its route")
    return out


def _interlock_problem(s: Any, lock: Any) -> str:
    """``""`` when ``lock.second`` leaves ``wait_row`` no earlier than ``lock.first`` is at
    rest at ``release_row`` (its weld there done), by the schedule's clock."""
    first = [a for a in s.of(lock.first) if a.row == lock.release_row]
    second = [a for a in s.of(lock.second) if a.row == lock.wait_row and a.kind != "move"]
    arrive = [a.end for a in first if a.kind == "move"] or [0.0]
    ready = max([a.end for a in first if a.kind == "weld"] or arrive)
    moved = [a for a in s.of(lock.second) if a.kind == "move" and a.row == lock.wait_row]
    leave = max([a.end for a in second] or [a.end for a in moved] or [0.0])
    if leave + 1e-6 < ready:
        return f"{lock.name}: robot {lock.second + 1} leaves at {leave:.4f} s, before {ready:.4f} s"
    return ""


def interference_check(saved: Any, station: Any) -> CheckResult:
    """The replay re-run from the files and compared with the recorded one (module
    docstring)."""
    from weldplan.multi.replay import replay_station

    if saved.schedule is None:
        return CheckResult("interference", False, "the plan records no schedule to replay")
    try:
        robots = [_replay_robot(saved, station, k) for k in range(len(saved.robots))]
        v = replay_station(robots, saved.schedule.interlocks, station.clearance)
    except (InputError, PlanningError) as exc:
        return CheckResult("interference", False, f"the replay cannot run: {exc}")
    rec = saved.replay
    said = _replay_line(v, saved.robots)
    if rec is None:
        agree, text = True, f"re-run (the plan records none): {said}"
    else:
        same = rec.min_distance == v.min_distance or (
            abs(rec.min_distance - v.min_distance) <= DISTANCE_TOL)  # fmt: skip
        agree = rec.ok == v.ok and same and (rec.clearance, rec.pairs) == (v.clearance, v.pairs)
        was = "" if agree else f"; recorded: {_replay_line(rec, saved.robots)}"
        text = f"re-run: {said}{was}"
    pair = () if v.ok else (too_close_line(saved, v),)
    return CheckResult("interference", agree, text, left_out=pair if agree else ())


#: the replay's line of a pair too close (weldplan.multi.replay): where each robot is, then
#: the distance found, the bodies and the clearance
_FAILURE = re.compile(r"^(.*) and (.*): ([0-9.]+) mm \((.*)\), not proven ([0-9.eE+-]+) mm apart$")
_AT = re.compile(r"^(\S+) (at rest at row (\d+)|moving rows (\d+) -> (\d+))$")


def too_close_line(saved: Any, v: Any) -> str:
    """What failed in a replay ``v`` (:class:`~weldplan.multi.schedule.ReplayVerdict`, not
    ok), in one line: the two robots, where each was (the row it rests at, or the rows it
    moves between, with the weld there from the schedule), the distance found against the
    clearance, the bodies, and how many more pairs failed. ``weldplan verify`` prints it as
    the robots too close (never as welds left out)."""
    if not v.failures:
        return f"robots closer than {v.clearance:g} mm: {_replay_line(v, saved.robots)}"
    m = _FAILURE.match(v.failures[0])
    if m is None:  # a line this reader does not know: as the replay wrote it
        return v.failures[0]
    a, b, dist, bodies, clearance = m.groups()
    more = len(v.failures) - 1
    tail = f"; {more} more pair(s) too close" if more else ""
    return (
        f"{_where(saved, a)} and {_where(saved, b)}: {dist} mm apart ({bodies}), clearance "
        f"{clearance} mm{tail}"
    )


def _where(saved: Any, text: str) -> str:
    """``robot1 at rest at row 3`` -> ``robot1 at rest at row 3 (weld 12)``: the weld the
    schedule records at that row (a move: ``(to weld 12)``, at the row it moves to)."""
    m = _AT.match(text)
    if m is None or saved.schedule is None:
        return text
    names = [r.name for r in saved.robots]
    if m.group(1) not in names:
        return text
    k = names.index(m.group(1))
    row = int(m.group(3) if m.group(3) is not None else m.group(5))
    weld = next((a.label for a in saved.schedule.of(k) if a.kind == "weld" and a.row == row), "")
    if not weld:
        return text
    return f"{text} (to weld {weld})" if m.group(3) is None else f"{text} (weld {weld})"


def _replay_robot(saved: Any, station: Any, k: int) -> Any:
    """Robot ``k`` as the replay reads it from the files (module docstring)."""
    from weldplan.multi.station import home_timing, replay_robot
    from weldplan.robot import load_robot
    from weldplan.station.mount import mount_tool

    spec, robot = station.robots[k], saved.robots[k]
    if spec.base is None and robot.base is not None:  # a searched base: the plan records it
        spec = dataclasses.replace(spec, base=robot.base)
    if robot.trajectory is None and spec.urdf is not None and spec.base is not None:
        # an idle robot stands at its home the whole cycle, as the plan replayed it
        arm = load_robot(spec.urdf, spec.opw)
        return replay_robot(robot.name, spec, home_timing(spec, arm), mount_tool(spec.tool, arm))
    if robot.trajectory is None or not saved.schedule.of(k):
        return replay_robot(robot.name, spec, None, None)
    timing = file_timing(saved.schedule, k, robot.trajectory)
    tool = mount_tool(spec.tool, load_robot(spec.urdf, spec.opw))
    return replay_robot(robot.name, spec, timing, tool)


def _replay_line(v: Any, robots: Any) -> str:
    """One line of a :class:`~weldplan.multi.schedule.ReplayVerdict`: ok or not, the pairs,
    the minimum distance and where."""
    md = "no pair may overlap" if np.isinf(v.min_distance) else f"min {v.min_distance:.4f} mm"
    if v.closest is not None:
        a, x, b, y = v.closest
        md += f" ({robots[a].name} row {x} / {robots[b].name} row {y})"
    head = "ok" if v.ok else f"robots closer than {v.clearance:g} mm"
    return f"{head} over {v.pairs} pairs of motions, {md}"
