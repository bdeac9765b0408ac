"""``weldplan verify`` of a station reads each robot's program back (weldplan.multi.programcheck):
its interlock signals must be exactly its side of the schedule's interlocks, each after the
target of its row. Two KR 150 crossing in the middle (tests/multi_fixtures.py) through the live
interference stage, which interlocks them; their programs rendered by the real posts (KRL and
RAPID) and then edited as a user might: a WAIT dropped, a set moved to another target, a signal
renumbered. And what verify says when the replay finds two robots too close: the robots, where
they are, the distance against the clearance, never "welds left out". Fast: no planning."""

from __future__ import annotations

import dataclasses
import re

import pytest


def _saved(tmp_path, post: str, locks=None, rows: bool = True):
    """The :class:`~weldplan.multi.saved.SavedStationPlan` of the crossing pair: the schedule
    and replay as the interference stage made them (or the schedule under ``locks``, made by
    hand), each robot's trajectory CSV and program (its signals as
    :func:`weldplan.multi.station.with_signals` gives them) written in ``tmp_path``; ``rows``:
    the route row of each timed row recorded (the identity here), as a station JSON has it."""
    from tests.test_multi_cli import CROSSING_BASES, _crossing_pair
    from weldplan.io.posts.krl import render_krl
    from weldplan.io.posts.rapid import render_rapid
    from weldplan.io.trajectory import trajectory_csv_text
    from weldplan.multi.saved import SavedRobot, SavedStationPlan
    from weldplan.multi.schedule import station_schedule
    from weldplan.multi.station import with_signals

    station, timings, plans, names, (out, schedule, verdict, _) = _crossing_pair(tmp_path)
    if locks is not None:
        ids = [p.program.weld_ids_by_row() for p in plans]
        schedule = station_schedule(names, timings, locks, weld_ids=ids)
        out = with_signals(list(plans), locks, names)
    saved_robots = []
    for k, (plan, t) in enumerate(zip(out, timings, strict=True)):
        stem = tmp_path / f"route_robot{k + 1}"
        traj = stem.with_name(f"{stem.name}_trajectory.csv")
        traj.write_text(trajectory_csv_text(t))
        prog = dataclasses.replace(plan.program.program, name=stem.name, tool_mass=1.0)
        if post == "krl":
            src, dat = render_krl(prog)
            files = (stem.with_suffix(".src"), stem.with_suffix(".dat"))
            files[0].write_text(src)
            files[1].write_text(dat)
        else:
            files = (stem.with_suffix(".mod"),)
            files[0].write_text(render_rapid(prog))
        ids = tuple(range(len(t.row_times))) if rows else None
        saved_robots.append(
            SavedRobot(names[k], None, CROSSING_BASES[k], (), None, traj, files, t.total, ids)
        )
    saved = SavedStationPlan(
        tmp_path / "route_station.json", None, tuple(saved_robots), None, schedule,
        schedule.cycle_time, "", verdict,
    )  # fmt: skip
    return saved


@pytest.mark.parametrize(("post", "rows"), [("krl", True), ("rapid", True), ("krl", False)])
def test_each_program_carries_exactly_its_side_of_the_interlocks(tmp_path, post, rows):
    from weldplan.multi.recheck import signal_checks

    # rows False: a station JSON saved before it recorded the route rows; the trajectory CSV's
    # step column stands in (every stop of these routes is reached by a motion)
    saved = _saved(tmp_path, post, rows=rows)
    locks = saved.schedule.interlocks
    assert locks  # the crossing needs at least one
    checks = signal_checks(saved)
    assert [c.name for c in checks] == ["robot1 signals", "robot2 signals"]
    for k, c in enumerate(checks):
        n = sum(i.first == k for i in locks) + sum(i.second == k for i in locks)
        assert c.ok, c.text
        assert f"exactly its {n} interlock signal(s)" in c.text


def _lines(path):
    return path.read_text().splitlines()


def test_a_dropped_wait_fails_naming_the_file_and_the_line_of_its_target(tmp_path):
    from weldplan.multi.programcheck import signals_check

    saved = _saved(tmp_path, "krl")
    lock = saved.schedule.interlocks[0]
    src = saved.robots[lock.second].program[0]
    lines = _lines(src)
    wait = f"WAIT FOR $IN[{lock.signal}]"
    (i,) = [n for n, ln in enumerate(lines) if ln.strip().startswith(wait)]
    move = lines[i - 1].strip()  # the wait follows the move to its target (and its weld)
    while not move.startswith(("PTP ", "LIN ")):
        i -= 1
        move = lines[i - 1].strip()
    del lines[[n for n, ln in enumerate(lines) if wait in ln][0]]
    src.write_text("\n".join(lines) + "\n")
    c = signals_check(saved, lock.second)
    assert not c.ok
    where = re.search(r"route_robot\d\.src, line (\d+): no WAIT FOR \$IN\[(\d+)\]", c.text)
    assert where is not None, c.text
    assert int(where.group(2)) == lock.signal and lock.name in c.text
    assert _lines(src)[int(where.group(1)) - 1].strip() == move
    assert signals_check(saved, lock.first).ok  # the other robot's program is untouched


def test_a_set_moved_to_another_target_or_renumbered_fails(tmp_path):
    from weldplan.multi.programcheck import signals_check

    saved = _saved(tmp_path, "rapid")
    lock = saved.schedule.interlocks[0]
    mod = saved.robots[lock.first].program[0]
    text = mod.read_text()
    lines = text.splitlines()
    (i,) = [n for n, ln in enumerate(lines) if re.match(r"\s*SetDO \w+, 1;", ln)]
    moves = [n for n, ln in enumerate(lines) if ln.strip().startswith("Move")]
    other = next(n for n in moves if n > i) if any(n > i for n in moves) else moves[0]
    line = lines.pop(i)
    lines.insert(other + 1 if other < i else other, line)  # right after another move
    mod.write_text("\n".join(lines) + "\n")
    c = signals_check(saved, lock.first)
    assert not c.ok
    assert "no SetDO" in c.text and "is not in the schedule" in c.text
    assert re.search(r"route_robot\d\.mod, line \d+: SetDO", c.text)
    # the signal renumbered where it stands
    mod.write_text(text.replace(f"do{lock.signal}_", f"do{lock.signal + 40}_"))
    c = signals_check(saved, lock.first)
    assert not c.ok and f"SetDO do{lock.signal + 40}_{lock.name}" in c.text


def test_a_program_outside_the_posts_grammar_is_named_by_file_and_line(tmp_path):
    from weldplan.multi.programcheck import signals_check

    saved = _saved(tmp_path, "krl")
    dat = saved.robots[0].program[1]
    lines = _lines(dat)
    lines.insert(3, "  DECL INT COUNT=0")
    dat.write_text("\n".join(lines) + "\n")
    c = signals_check(saved, 0)
    assert not c.ok and "route_robot1.dat, line 4: not a line weldplan writes" in c.text


def test_signals_at_weld_rows_follow_the_weld_target_named_by_the_schedule(tmp_path):
    from weldplan.multi.programcheck import signals_check
    from weldplan.multi.schedule import Interlock

    # robot 2 may not leave its weld (row 1) before robot 1 has welded its own (row 1)
    lock = Interlock("Z9", first=0, release_row=1, second=1, wait_row=1, signal=5)
    saved = _saved(tmp_path, "krl", locks=(lock,))
    assert [a.label for a in saved.schedule.of(1) if a.kind == "weld"] == ["w1"]
    assert signals_check(saved, 0).ok and signals_check(saved, 1).ok
    src = saved.robots[1].program[0]
    lines = _lines(src)
    i = next(n for n, ln in enumerate(lines) if "WAIT FOR $IN[5]" in ln)
    assert "spot w1" in lines[i - 1]  # after the weld at its weld target
    del lines[i]
    src.write_text("\n".join(lines) + "\n")
    c = signals_check(saved, 1)
    assert not c.ok and "no WAIT FOR $IN[5] after XP0001 (weld w1)" in c.text


def test_robots_too_close_are_said_as_such_with_rows_distance_and_clearance(tmp_path):
    from tests.test_multi_cli import _crossing_saved
    from weldplan.commands.verify import _partial_lines
    from weldplan.multi.recheck import interference_check
    from weldplan.multi.replay import replay_station
    from weldplan.station.recheck import CheckResult, Verdict

    station, saved, _, rr = _crossing_saved(tmp_path)
    # the plan without its interlocks, recorded as the replay finds it: robots too close
    bare = dataclasses.replace(saved, schedule=dataclasses.replace(saved.schedule, interlocks=()))
    v = replay_station(rr, (), station.clearance)
    assert not v.ok
    check = interference_check(dataclasses.replace(bare, replay=v), station)
    assert check.ok  # the re-run agrees with the record: a partial plan, exit 3
    (line,) = check.left_out
    at = r"(robot\d) (at rest at row \d+|moving rows \d+ -> \d+)( \((?:to )?weld w\d\))?"
    where = re.match(at + " and " + at + r": ([0-9.]+) mm apart \((.+)\), clearance 5 mm", line)
    assert where is not None, line
    assert {where.group(1), where.group(4)} == {"robot1", "robot2"}
    assert float(where.group(7)) < station.clearance
    unreached = CheckResult("allocation", True, "", left_out=("15",))
    legs = CheckResult("robot1", True, "", left_out=("7->1", "1->5"))
    said = _partial_lines(Verdict((unreached, legs, check)))
    assert said == [
        "welds left out: 15",
        "transitions left out: 7->1, 1->5",
        f"robots too close by the replay: {line}",
    ]
