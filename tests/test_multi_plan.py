"""``weldplan.plan`` on a station of two robots (weldplan.multi.station): the demo part, the
shared spot gun on two KUKA KR 150 at given bases on either side of the part, six of the demo's
welds (15 among them: no robot reaches it), each robot starting and ending at its home. Slow: it
runs the whole single-robot pipeline once per robot (minutes wall on a loaded machine). The
station's interference stage is tested fast on two crossing robots with synthetic routes
(tests/multi_fixtures.py)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import require_shared

ROOT = Path(__file__).resolve().parents[1]
#: (x, y, z mm, yaw deg), part frame: behind the demo part facing it, and in front facing back
BASES = ((448.1, 95.3, 652.7, -7.5), (2450.0, -150.0, 652.7, 180.0))
#: the demo welds of the station
IDS = ("1", "5", "7", "9", "13", "15")
#: deg: each robot's home, its arm turned away from the other (at the conventional home, A1 0,
#: the two arms meet over the part)
HOME = (90.0, -90.0, 90.0, 0.0, 0.0, 0.0)


def _station(folder: Path | None = None):
    """The demo station with two robots at BASES; with ``folder``, only the welds IDS (a
    welds file written there)."""
    import weldplan
    from weldplan.io.joints import Joints, read_joints
    from weldplan.weld import demo_part

    require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    st = weldplan.load_station(ROOT / "examples" / "demo_station.toml")
    home = dataclasses.replace(st.robots[0].settings, home=HOME)
    specs = tuple(dataclasses.replace(st.robots[0], base=b, settings=home) for b in BASES)
    st = dataclasses.replace(st, robots=specs)
    if folder is None:
        return st
    j = read_joints(demo_part.DEMO_JOINTS)
    k = [j.ids.index(i) for i in IDS]
    sub = Joints(ids=IDS, xyz=np.asarray(j.xyz)[k], directions=np.asarray(j.directions)[k])
    sub.to_csv(folder / "welds.csv")
    part = dataclasses.replace(st.part, mesh=demo_part.DEMO_PART, welds=folder / "welds.csv")
    return dataclasses.replace(st, part=part)


def _synthetic_plan(robot, timing):
    """A :class:`~weldplan.station.pipeline.Plan` holding only what the station's interference
    stage reads: the robot at its base and a program over ``timing``'s rows (no tool)."""
    from weldplan.io.posts.program import RobotProgram, Target
    from weldplan.robot.program import ProgramBuild
    from weldplan.station.pipeline import Plan
    from weldplan.station.robotstage import RobotResult

    Q = timing.q[[int(np.argmin(np.abs(timing.t - t))) for t in timing.row_times]]
    welds = set(timing.weld_rows.tolist())
    targets = tuple(
        Target("weld" if r in welds else "via", r, f"w{r}" if r in welds else "", np.eye(4), q,
               np.zeros(3, bool), "joint", 0.0, 1000.0)
        for r, q in enumerate(Q)
    )  # fmt: skip
    program = RobotProgram(
        "p", robot.name, robot.joint_names, targets, np.eye(4), 0.0, np.zeros(3), np.eye(4)
    )
    build = ProgramBuild(program, timing, timing.total, 1000.0, 0.0)
    return Plan(None, 0, None, None, None, robot=RobotResult(None, None, None, robot),
                program=build)  # fmt: skip


def test_the_interference_stage_interlocks_two_crossing_robots_and_the_replay_proves_it():
    from tests import multi_fixtures as mf
    from weldplan.io.posts.program import SignalAction
    from weldplan.multi.station import _interference

    robots, timings = mf.pair()
    st = _station()
    assert Path(st.robots[0].urdf).resolve() == mf.urdf().resolve()  # the same KR 150
    bases = ((-1500.0, 0.0, 0.0, 0.0), (1500.0, 0.0, 0.0, 180.0))  # as mf.pair places them
    station = dataclasses.replace(
        st, robots=tuple(dataclasses.replace(st.robots[0], base=b) for b in bases)
    )
    plans = [_synthetic_plan(r, t) for r, t in zip(robots, timings, strict=True)]
    seconds: dict[str, float] = {}
    out, schedule, verdict, line = _interference(station, plans, ("robot1", "robot2"), seconds)
    assert verdict.ok and verdict.min_distance >= station.clearance
    assert {"interference", "zones", "replay"} <= set(seconds)
    (lock,) = schedule.interlocks
    # each program carries its side of the interlock, at the route row of the timed row
    first, second = out[lock.first].program.program, out[lock.second].program.program
    assert first.signals == (SignalAction(lock.release_row, "set", 1, lock.name, "robot2"),)
    assert second.signals == (SignalAction(lock.wait_row, "wait", 1, lock.name, "robot1"),)
    assert all(
        p.program.program.targets is q.program.program.targets
        for p, q in zip(out, plans, strict=True)
    )
    # the waiting robot's cycle grows by its wait, exactly
    w = schedule.waiting
    assert w[lock.first] == 0.0 and w[lock.second] > 0.0
    for r, t in enumerate(timings):
        assert schedule.cycle_times[r] == pytest.approx(t.total + w[r], abs=1e-9)
    assert "1 interlocks" in line and "replay ok" in line


@pytest.mark.parametrize("distance", [3000.0, 12000.0])
def test_an_idle_robot_stands_at_its_home_in_the_interference_check_and_the_replay(distance):
    """Robot 2 has no weld: it stands at its home (the conventional one: its arm stretched
    towards robot 1) the whole cycle. 3 m apart robot 1's sweep runs into it, which no interlock
    can order (an idle robot waits for nothing): the replay fails naming robot 2 at rest at its
    home. 12 m apart the replay checks robot 1's every motion against it and finds it clear."""
    from tests import multi_fixtures as mf
    from weldplan.multi.station import _interference

    robots, timings = mf.pair(distance)
    st = _station()
    bases = ((-distance / 2, 0.0, 0.0, 0.0), (distance / 2, 0.0, 0.0, 180.0))
    conventional = dataclasses.replace(st.robots[0].settings, home=None)
    station = dataclasses.replace(st, robots=tuple(
        dataclasses.replace(st.robots[0], base=b, settings=conventional) for b in bases
    ))  # fmt: skip
    plans = [_synthetic_plan(robots[0], timings[0]), None]
    out, schedule, verdict, line = _interference(station, plans, ("robot1", "robot2"), {})
    assert out[1] is None and schedule.of(1) == ()
    moves = 2 * int(np.count_nonzero(timings[0].stops)) - 1  # robot 1's rests and moves
    if distance > 5000.0:
        assert verdict.ok and verdict.pairs == moves and np.isfinite(verdict.min_distance)
    else:
        assert not verdict.ok and "that no interlock can order" in line
        assert "robot2 at rest at row 0" in verdict.failures[0]


def test_a_home_that_collides_or_is_out_of_limits_is_refused_naming_the_file_line_and_key(
    tmp_path, capsys
):
    """Two robots facing each other 2 m apart across the demo part: at the conventional
    home their arms meet, a one-line error asking for a home; a home out of A2's limits names
    its line. Refused before any robot is studied."""
    from tests.cli_helpers import one_line_error, run_cli
    from tests.test_multi_cli import _station_toml

    f = _station_toml(tmp_path / "a", ["1", "9"], bases=BASES, homes=None)
    assert run_cli(["plan", str(f), "-o", str(tmp_path / "r.csv")]) == 2
    line = one_line_error(capsys)
    at = [n for n, ln in enumerate(f.read_text().splitlines(), start=1) if ln == "[[robot]]"][1]
    assert f"station.toml, line {at}, field 'robot.home': robot 2: at its home it comes" in line
    assert "give each robot a home clear of the others" in line
    homes = ((90.0, -90.0, 90.0, 0.0, 0.0, 0.0), (90.0, 0.0, 90.0, 0.0, 0.0, 0.0))
    f = _station_toml(tmp_path / "b", ["1", "9"], homes=homes)
    assert run_cli(["plan", str(f), "-o", str(tmp_path / "r.csv")]) == 2
    line = one_line_error(capsys)
    at = [n for n, ln in enumerate(f.read_text().splitlines(), start=1) if ln.startswith("home")]
    assert f"station.toml, line {at[1]}, field 'robot.home': robot 2: home A2 = 0 deg" in line
    assert not list(tmp_path.glob("r*"))


@pytest.mark.slow
def test_two_robots_share_the_demo_welds_and_each_plans_its_share(tmp_path):
    import weldplan
    from weldplan.multi.station import NO_INTERFERENCE, StationPlan

    p = weldplan.plan(_station(tmp_path), rng=0)
    assert isinstance(p, StationPlan)
    a = p.allocation
    idle = [n for n, sub in zip(a.robots, p.plans, strict=True) if sub is None]
    assert not idle or not any(a.welds_of(a.robots.index(n)) for n in idle)
    if idle:  # the allocation's passes gave one robot every weld: nothing to share
        pytest.xfail(f"issue 30: the demo station leaves {', '.join(idle)} idle (the robots "
                     "facing each other meet at their homes)")  # fmt: skip
    every = set(p.plans[0].cell.joints.ids) | set(p.plans[1].cell.joints.ids)
    assert [u.weld for u in a.unreached] == ["15"]  # A2 past its limit from both bases
    assert every | {"15"} == set(IDS)
    for r, sub in enumerate(p.plans):
        # each robot's plan is over its share exactly, and its program welds every weld or
        # says which it left out
        assert set(sub.cell.joints.ids) == set(a.welds_of(r))
        assert len(sub.station.robots) == 1 and sub.station.robots[0].base == BASES[r]
        timing = sub.program.timing
        assert timing.total >= timing.weld_time * len(sub.robot.robot_route.weld_ids) - 1e-9
    assert p.report.bound.value <= a.cycle_time + 1e-9
    # the allocate-plan rounds (weldplan.multi.calibrate): the plans are the best round's, and
    # the pose-free bound is below the timed cycle of every round
    assert 1 <= len(p.rounds) <= 3
    assert max(p.timed_cycles) == pytest.approx(min(r.timed_cycle for r in p.rounds))
    assert p.report.bound.value <= min(r.timed_cycle for r in p.rounds)
    rows = dict(p.summary_rows())
    assert {f"robot robot{k}" for k in (1, 2)} <= set(rows)
    assert np.isfinite(p.cycle_time) and p.cycle_time > 0
    # the schedule runs each robot's own timing and its waits at the interlocks: the station's
    # cycle is the last robot's end, each robot's end its own cycle plus its waits, and every
    # weld of every program on the clock under its id
    s = p.schedule
    assert s is not None and p.cycle_time == s.cycle_time >= max(p.timed_cycles)
    for r, sub in enumerate(p.plans):
        assert s.cycle_times[r] == pytest.approx(p.timed_cycles[r] + s.waiting[r], abs=1e-9)
        welded = {t.joint_id for t in sub.program.program.targets if t.kind == "weld"}
        assert {a.label for a in s.of(r) if a.kind == "weld"} == welded
        # each program carries its side of every interlock, named by route row
        prog = sub.program.program
        mine = [(i.signal, "set") for i in s.interlocks if i.first == r]
        mine += [(i.signal, "wait") for i in s.interlocks if i.second == r]
        assert sorted((x.signal, x.action) for x in prog.signals) == sorted(mine)
        assert {x.row for x in prog.signals} <= {t.row for t in prog.targets}
    # each program starts and ends at its robot's home: the legs to the first weld and back
    # are motions of the schedule, so an interlock can hold a robot at home while the other
    # works (before homes, the two guns overlapped at the programs' first welds, where no
    # interlock can part them: the replay failed there)
    for sub in p.plans:
        tg = sub.program.program.targets
        assert tg[0].kind == tg[-1].kind == "home"
        assert np.allclose(np.degrees(tg[0].q), HOME) and np.array_equal(tg[0].q, tg[-1].q)
        timing = sub.program.timing
        assert np.allclose(timing.q[0], np.radians(HOME)) and np.allclose(timing.q[-1], timing.q[0])
    assert s.interlocks and p.replay is not None and p.replay.closest != (0, 0, 1, 0)
    assert rows["interference"] != NO_INTERFERENCE
    # on this station the replay still fails: robot 1's exit from a weld near robot 2 and its
    # detour meet robot 2 in every configuration it takes (its column), which no interlock can
    # order; each robot is planned blind of the others' bodies (the report says so)
    assert p.replay.ok == ("REPLAY FAILED" not in rows["interference"])
    assert p.replay.ok or "no interlock can order" in rows["interference"]
