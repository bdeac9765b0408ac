"""``weldplan plan station.toml`` with several robots, its files, and ``weldplan verify`` of the
station JSON (issue 30, item 5): the demo part, the shared spot gun on two KUKA KR 150 at given
bases (tests/test_multi_plan.py's), a station file written in ``tmp_path``.

The fast tests are the bad inputs (one line, exit 2, naming the file and the key) and verify's
re-run of the replay on two crossing robots (tests/multi_fixtures.py) saved by hand. The slow ones
plan: the command line on five welds both robots reach (each robot from its home, its program's
first and last motion; every file; verify re-runs the replay and agrees; a corrupted station
JSON refused by name), and the library on six (weld 15 no robot reaches) with an interlock made
by hand, written into both programs and re-checked against the schedule."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

from tests.cli_helpers import one_line_error, run_cli
from tests.conftest import require_shared

#: (x, y, z mm, yaw deg), part frame: behind the demo part facing it, and in front facing back
BASES = ((448.1, 95.3, 652.7, -7.5), (2450.0, -150.0, 652.7, 180.0))
#: a demo weld neither robot reaches (A2 past its limit from both bases)
UNREACHED = "15"
#: deg: each robot's home, its arm turned away from the other (at the conventional home, A1 0,
#: the two arms meet over the part)
HOMES = ((90.0, -90.0, 90.0, 0.0, 0.0, 0.0),) * 2


def _station_toml(
    folder: Path, ids, bases=BASES, extra: str = "", mesh: str | None = None, homes=HOMES
):
    """A station file in ``folder`` with the demo welds ``ids`` and a robot at each base, at
    its home (``homes``; ``None``: no home key)."""
    from weldplan.io.joints import Joints, read_joints
    from weldplan.weld import demo_part

    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    gun = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    folder.mkdir(parents=True, exist_ok=True)
    j = read_joints(demo_part.DEMO_JOINTS)
    k = [j.ids.index(i) for i in ids]
    welds = Joints(ids=tuple(ids), xyz=np.asarray(j.xyz)[k], directions=np.asarray(j.directions)[k])
    welds.to_csv(folder / "welds.csv")
    homes = (None,) * len(bases) if homes is None else homes
    robots = "".join(
        f'\n[[robot]]\nurdf = "{urdf}"\nbase = {list(b)}\nweld_time = 0.5\n'
        + ("" if h is None else f"home = {list(h)}\n")
        + f'{extra}\n[robot.tool]\nfile = "{gun}"\n'
        for b, h in zip(bases, homes, strict=True)
    )
    text = f'seed = 0\n[part]\nmesh = "{mesh or demo_part.DEMO_PART}"\nwelds = "welds.csv"\n'
    (folder / "station.toml").write_text(text + "[tool_settings]\ncone = 15.0\n" + robots)
    return folder / "station.toml"


# ------------------------------------------------------------------ bad input, one line, exit 2
def test_two_robots_at_the_same_place_are_refused_naming_the_file_line_and_key(tmp_path, capsys):
    f = _station_toml(tmp_path, ["1", "9"], bases=(BASES[0], (448.1, 95.3, 0.0, 90.0)))
    assert run_cli(["plan", str(f), "-o", str(tmp_path / "r.csv")]) == 2
    line = one_line_error(capsys)
    lines = f.read_text().splitlines()
    at = [n for n, ln in enumerate(lines, start=1) if ln.startswith("base =")][1]
    assert f"station.toml, line {at}, field 'robot.base'" in line
    assert "robot 2 stands 0.0 mm from robot 1" in line


def test_a_base_inside_the_part_is_refused_naming_the_file_and_key(tmp_path, capsys):
    inside = (1400.0, -60.0, 680.0, 0.0)  # among the demo welds, on the part
    f = _station_toml(tmp_path, ["1", "9"], bases=(BASES[0], inside))
    out = tmp_path / "r.csv"
    assert run_cli(["plan", str(f), "-o", str(out)]) == 2
    line = one_line_error(capsys)
    assert "station.toml, field 'robot.base'" in line and "robot 2's base" in line
    assert not list(tmp_path.glob("r*"))  # nothing written


def test_an_unknown_key_and_a_missing_mesh_are_one_line_errors(tmp_path, capsys):
    f = _station_toml(tmp_path / "a", ["1", "9"], extra="weld_tme = 0.5\n")
    assert run_cli(["plan", str(f), "-o", str(tmp_path / "r.csv")]) == 2
    assert "field 'robot.weld_tme': unknown key 'weld_tme'" in one_line_error(capsys)
    f = _station_toml(tmp_path / "b", ["1", "9"], mesh=str(tmp_path / "nowhere.stl"))
    assert run_cli(["plan", str(f), "-o", str(tmp_path / "r.csv")]) == 2
    assert "field 'part.mesh': no such file" in one_line_error(capsys)


def test_verify_refuses_a_station_json_that_is_not_json_naming_the_line(tmp_path, capsys):
    from weldplan.multi.saved import STATION_FORMAT

    bad = tmp_path / "s.json"
    bad.write_text(f'{{\n "format": "{STATION_FORMAT}",\n "robots": [\n}}\n')
    assert run_cli(["verify", str(bad)]) == 2
    assert "s.json, line 4: not valid JSON" in one_line_error(capsys)
    bad.write_text(json.dumps({"format": STATION_FORMAT, "robots": []}))
    assert run_cli(["verify", str(bad)]) == 2
    assert "field 'allocation'" in one_line_error(capsys)


def test_the_station_page_and_its_gantt_png_are_named_and_checked_before_any_work(tmp_path):
    from weldplan.errors import InputError
    from weldplan.multi.saved import station_paths
    from weldplan.station.model import OutputSpec

    out = OutputSpec(csv=tmp_path / "r.csv", html=tmp_path / "cell.html")
    paths = station_paths(out, 2)
    assert (paths.html, paths.gantt) == (tmp_path / "cell.html", tmp_path / "cell_gantt.png")
    assert all("html" not in kinds for kinds in paths.robots)  # one page, the station's
    bad = dataclasses.replace(out, html=tmp_path / "nowhere" / "cell.html")
    with pytest.raises(InputError, match="field 'station html': folder .* does not exist"):
        station_paths(bad, 2)


# --------------------------------------------------------------- the command line, planned once
@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    """``weldplan plan station.toml -o out/route.csv --json out/route.json --post krl --html
    out/route.html`` on five demo welds both robots can serve; ``(exit code, out folder)``."""
    import contextlib
    import io

    folder = tmp_path_factory.mktemp("station")
    f = _station_toml(folder, ["1", "5", "7", "9", "13"])
    out = folder / "out"
    out.mkdir()
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = run_cli(["plan", str(f), "-o", str(out / "route.csv"), "--json",
                        str(out / "route.json"), "--post", "krl", "--html",
                        str(out / "route.html"), "--quiet"])  # fmt: skip
    return code, out


@pytest.mark.slow
def test_the_command_line_writes_every_robots_files_and_the_station_json(cli_run):
    from weldplan.io.posts.parse import parse_krl
    from weldplan.multi.saved import load_station_plan

    code, out = cli_run
    saved = load_station_plan(out / "route_station.json")
    assert not saved.report.ours.unreached and saved.replay is not None
    locks = saved.schedule.interlocks
    partial = False  # a weld some robot's route left out
    assert [r.name for r in saved.robots] == ["robot1", "robot2"]
    shares = [set(r.welds) for r in saved.robots]
    assert shares[0] | shares[1] == {"1", "5", "7", "9", "13"} and not shares[0] & shares[1]
    for k, r in enumerate(saved.robots, start=1):
        if not r.welds:
            continue
        assert r.route == out / f"route_robot{k}.json" and r.route.is_file()
        assert (out / f"route_robot{k}.csv").is_file() and r.trajectory.is_file()
        src, dat = (p.read_text() for p in r.program)
        prog = parse_krl(src, dat)
        assert prog.name == f"route_robot{k}"
        welds = [ln.split("; weld ")[1] for ln in dat.splitlines() if "; weld " in ln]
        # the program welds its share but the welds its route left out, each with its cause
        served, left = _route_verdicts(r.route)
        assert set(served) | set(left) == set(r.welds) and set(welds) == set(served)
        assert all(left.values())
        partial = partial or bool(left)
        # the program starts and ends at the robot's home, its axis values as the file gives
        assert prog.moves[0][:2] == ("PTP", "XHOME") and prog.moves[-1][:2] == ("PTP", "XHOME")
        assert np.allclose(prog.axes["XHOME"], HOMES[k - 1], atol=1e-5)
        # the program carries its side of every interlock of the schedule, and no other signal
        mine = [("set", i.signal, i.name) for i in locks if i.first == k - 1]
        mine += [("wait", i.signal, i.name) for i in locks if i.second == k - 1]
        assert sorted(s[1:] for s in prog.signals) == sorted(mine)
    # exit 3: a replay that finds robots too close, or a weld left out
    assert code == (0 if saved.replay.ok and not partial else 3)
    # the programs start at the homes, clear of each other: the two guns no longer stand
    # overlapping at the cycle's start (before homes: at the programs' first welds, which no
    # interlock can order); what the replay still finds is named
    assert saved.replay.closest != (0, 0, 1, 0)
    assert saved.replay.ok or "REPLAY FAILED" in saved.interference
    # --html: the station's page (both robots on one slider, the Gantt chart under it) and the
    # chart as a PNG beside it; no robot's own page
    page = (out / "route.html").read_text()
    assert "weldplan-gantt" in page and "robot2" in page
    assert (out / "route_gantt.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(out.glob("route_robot*.html"))


@pytest.mark.slow
def test_verify_of_the_station_json_re_runs_the_replay_and_agrees(cli_run, capsys):
    _, out = cli_run
    capsys.readouterr()
    from weldplan.multi.saved import load_station_plan

    ok = load_station_plan(out / "route_station.json").replay.ok
    assert run_cli(["verify", str(out / "route_station.json")]) == (0 if ok else 3)
    said = capsys.readouterr()
    for name in ("allocation ok", "robot1 ok", "robot2 ok", "schedule ok"):
        assert name in said.out
    # the re-run agrees with the record (the home legs re-checked in each robot's route, the
    # replay re-run from the trajectory files, home to home)
    assert "interference ok: re-run: " + ("ok over" if ok else "robots closer") in said.out
    if not ok:
        # said as robots too close: where each stands, the distance and the clearance
        assert re.search(
            r"weldplan verify: ok, robots too close by the replay: robot\d .+: [0-9.]+ mm apart "
            r"\(.+\), clearance 5 mm",
            said.err,
        )
    # every weld is in a share: only a weld a robot's route left out (with its cause in the
    # route JSON) is said left out
    left = set().union(*(_route_verdicts(r.route)[1] for r in _saved(out).robots if r.welds))
    assert ("welds left out" in said.err) == bool(left)


def _route_verdicts(route: Path) -> tuple[list[str], dict[str, str]]:
    """``(welds served, {weld left out: its cause})`` of a robot's route JSON."""
    rr = json.loads(route.read_text())["tool"]["robot"]
    detail = rr.get("detail") or [""] * len(rr["status"])
    rows = list(zip(rr["weld_ids"], rr["status"], detail, strict=True))
    return [w for w, st, _ in rows if st == "ok"], {w: d for w, st, d in rows if st != "ok"}


def _saved(out: Path):
    from weldplan.multi.saved import load_station_plan

    return load_station_plan(out / "route_station.json")


def _corrupt(out: Path, tmp: Path, edit) -> Path:
    """A copy of the station's files in ``tmp`` with the station JSON changed by ``edit``."""
    import shutil

    shutil.copytree(out, tmp, dirs_exist_ok=True)
    p = tmp / "route_station.json"
    d = json.loads(p.read_text())
    edit(d)
    p.write_text(json.dumps(d))
    return p


@pytest.mark.slow
def test_a_corrupted_station_json_is_refused_naming_the_field_or_the_check(
    cli_run, tmp_path, capsys
):
    _, out = cli_run
    p = _corrupt(out, tmp_path / "a", lambda d: d.pop("allocation"))
    assert run_cli(["verify", str(p)]) == 2
    assert "field 'allocation'" in one_line_error(capsys)

    def twice(d):  # robot 2's first weld in robot 1's share too
        ours = d["allocation"]["ours"]
        ours["shares"][0]["order"].append(ours["shares"][1]["order"][0])

    def late(d):  # robot 1's last activity ends 0.5 s later than its trajectory
        acts = [a for a in d["schedule"]["activities"] if a[0] == 0]
        acts[-1][3] += 0.5

    def replay(d):  # a replay recorded clear: the re-run finds the robots too close
        d["replay"].update(ok=True, min_distance=50.0, failures=[])

    def unlocked(d):  # the interlocks deleted: the re-run checks more pairs than recorded
        assert d["schedule"]["interlocks"]
        d["schedule"]["interlocks"] = []

    for name, edit, check in (("b", twice, "allocation"), ("c", late, "schedule"),
                              ("d", replay, "interference"),
                              ("e", unlocked, "interference")):  # fmt: skip
        capsys.readouterr()
        assert run_cli(["verify", str(_corrupt(out, tmp_path / name, edit))]) == 1
        assert f"{check} FAILED" in capsys.readouterr().err


# ------------------------------------------------------ the library with a hand-made interlock
@pytest.fixture(scope="module")
def splan(tmp_path_factory):
    import weldplan

    f = _station_toml(tmp_path_factory.mktemp("lib"), ["1", "5", "7", "9", "13", UNREACHED])
    return weldplan.plan(weldplan.load_station(f), rng=0)


def _both_planned(splan) -> None:
    """The interlock tests need a program on each robot: where the planner leaves a robot
    idle, an expected failure naming it (issue 30: on the demo part the two robots facing each
    other meet at their homes, and the passes that keep those welds apart can give one robot
    every weld)."""
    idle = [n for n, p in zip(splan.allocation.robots, splan.plans, strict=True) if p is None]
    if idle:
        pytest.xfail(f"issue 30: the planned station leaves {', '.join(idle)} idle, so there is "
                     "no interlock between two programs to write")  # fmt: skip


def _interlocked(splan):
    """``splan`` with one interlock: robot 2 may not leave its first stop before robot 1 is
    at rest, its weld done, at its last stop (in the schedule, in both programs as the planner
    puts it, and the replay run again under it, as the planner runs it)."""
    from weldplan.multi.replay import replay_station
    from weldplan.multi.schedule import Interlock, station_schedule
    from weldplan.multi.station import _replay_robots, with_signals

    timings = [p.program.timing for p in splan.plans]
    last = int(np.flatnonzero(timings[0].stops)[-1])
    first = int(np.flatnonzero(timings[1].stops)[0])
    lock = Interlock("Z1", first=0, release_row=last, second=1, wait_row=first, signal=7)
    ids = [p.program.weld_ids_by_row() for p in splan.plans]
    sched = station_schedule(splan.allocation.robots, timings, [lock], weld_ids=ids)
    names = splan.allocation.robots
    plans = with_signals(list(splan.plans), [lock], names)
    st = splan.station
    replay = replay_station(_replay_robots(st, plans, names), (lock,), st.clearance)
    return dataclasses.replace(splan, schedule=sched, plans=tuple(plans), replay=replay), lock


@pytest.mark.slow
def test_an_interlock_is_written_into_both_programs_and_read_back(splan, tmp_path):
    from weldplan.io.posts.parse import parse_rapid

    _both_planned(splan)
    from weldplan.multi.programcheck import signals_check
    from weldplan.multi.saved import load_station_plan, robot_plans, station_paths, write_station
    from weldplan.station.model import OutputSpec

    sp, lock = _interlocked(splan)
    assert sp.schedule.waiting[1] > 0  # robot 2 really waits
    paths = station_paths(OutputSpec(csv=tmp_path / "route.csv", post="rapid"), 2)
    write_station(sp, paths)
    plans = robot_plans(sp)
    for k, action in ((0, "set"), (1, "wait")):
        mod = parse_rapid(paths.robots[k]["post"].read_text())
        prog = plans[k].program.program
        assert [(a.action, a.signal, a.name) for a in prog.signals] == [(action, 7, lock.name)]
        ((point, act, n, name),) = mod.signals
        assert (act, n, name) == (action, 7, lock.name)
        # p0005 -> target 5; jhome: robot 1 sets it back home, robot 2 waits at home
        at = {"set": -1, "wait": 0}[action] if point == "jhome" else int(point[1:])
        row = prog.targets[at].row
        timed = lock.release_row if k == 0 else lock.wait_row
        assert row == int(np.asarray(plans[k].program.row)[timed])
        assert mod.resets == ([(7, lock.name)] if action == "set" else [])
    # verify's program check finds each side at the target the schedule names, jhome included
    saved = load_station_plan(paths.station)
    for k in (0, 1):
        got = signals_check(saved, k)
        assert got.ok, got.text


@pytest.mark.slow
def test_the_saved_station_round_trips_and_verify_checks_the_interlock(splan, tmp_path, capsys):
    import weldplan

    _both_planned(splan)
    sp, lock = _interlocked(splan)
    path = weldplan.save_station_plan(sp, tmp_path / "cell_station.json")
    assert (tmp_path / "cell_robot1.json").is_file()
    saved = weldplan.load_station_plan(path)
    assert saved.schedule.interlocks == (lock,)
    assert saved.schedule.cycle_times == pytest.approx(sp.schedule.cycle_times, abs=1e-6)
    assert saved.report.ours.unreached[0].weld == UNREACHED
    assert saved.rounds == tuple(sp.rounds) and saved.rounds  # the allocate-plan rounds
    v = saved.verify()
    assert v["rounds"].ok, v["rounds"].text
    # left out: the weld no robot reaches, and a pair the replay (recorded and re-run) finds
    # too close, if any, named by where each robot is: robot 2 waits at home until robot 1 is
    # back at its own
    assert v.ok and v.exit_code == 3 and v.left_out[0] == UNREACHED
    assert len(v.left_out) == (1 if sp.replay.ok else 2)
    if not sp.replay.ok:
        assert re.match(r"robot\d (at rest|moving)", v.left_out[1]), v.left_out[1]
    assert "1 interlock(s) hold" in v["schedule"].text
    # robot 2's wait taken out and its later activities moved up: it leaves before robot 1 is
    # ready, and only the interlock says so (its moves and welds still match its trajectory)
    d = json.loads(path.read_text())
    acts = [a for a in d["schedule"]["activities"] if a[0] == 1]
    k = next(i for i, a in enumerate(acts) if a[1] == "wait")
    gone = acts[k][3] - acts[k][2]
    acts[k][3] -= gone
    for a in acts[k + 1 :]:
        a[2], a[3] = a[2] - gone, a[3] - gone
    path.write_text(json.dumps(d))
    v = weldplan.load_station_plan(path).verify()
    assert (
        not v.ok and not v["schedule"].ok and f"{lock.name}: robot 2 leaves" in v["schedule"].text
    )


@pytest.mark.slow
def test_the_summary_and_the_exit_say_what_is_left_out_and_a_failed_replay(splan):
    from weldplan.multi.saved import robot_plans
    from weldplan.multi.schedule import ReplayVerdict
    from weldplan.station.summary import station_partial, station_rows

    plans = robot_plans(splan)
    rows = dict(station_rows(splan, plans))
    locks = splan.schedule.interlocks
    for r, name in enumerate(splan.allocation.robots):
        n = len(splan.allocation.welds_of(r))
        if not n:  # a robot the allocation gave no weld stands at its home
            assert splan.plans[r] is None and rows[f"robot {name}"].startswith("idle")
            continue
        assert rows[f"robot {name}"].startswith(f"{n} welds, cycle ")
        sets, waits = sum(i.first == r for i in locks), sum(i.second == r for i in locks)
        assert f"interlocks: {sets} set, {waits} wait" in rows[f"robot {name}"]
    assert rows["station cycle"].startswith(f"{splan.schedule.cycle_time:.2f} s")
    # weld 15 no robot reaches, and any weld a robot's failed share gave up that no other
    # robot reaches (in the allocation's unreached, with the planner's words)
    un = [u.weld for u in splan.allocation.unreached]
    assert UNREACHED in un
    unreached = f"{len(un)} weld(s) no robot reaches ({', '.join(un)})"
    # the replay's verdict is said, and a failed one is a cause of exit 3
    said = "replay ok" if splan.replay.ok else "replay FAILED"
    assert rows["interference"].startswith(said)
    # and each weld a robot's plan left out, under its name
    left = [f"{n}: {ln}" for n, p in zip(splan.allocation.robots, plans, strict=True)
            if p is not None for ln in p.partial()]  # fmt: skip
    clear = ReplayVerdict(True, 5.0, 12.5, (0, 4, 1, 2), 12)
    assert station_partial(dataclasses.replace(splan, replay=clear), plans) == [unreached, *left]
    close = ReplayVerdict(False, 5.0, 0.0, (0, 0, 1, 0), 12, ("robot1 at rest at row 0 ...",))
    lines = station_partial(dataclasses.replace(splan, replay=close), plans)
    assert lines[: 1 + len(left)] == [unreached, *left] and len(lines) == 2 + len(left)
    assert lines[-1].startswith("the replay found robots too close") and "0.0 mm" in lines[-1]


@pytest.mark.slow
def test_the_command_line_exits_3_on_a_failed_replay_alone(splan, capsys):
    from weldplan.commands._station_plan import _exit_code
    from weldplan.multi.saved import robot_plans
    from weldplan.multi.schedule import ReplayVerdict

    plans = robot_plans(splan)
    assert _exit_code(splan, plans) == 3  # weld 15: no robot reaches it
    capsys.readouterr()
    reached = dataclasses.replace(splan.report.ours, unreached=())
    report = dataclasses.replace(splan.report, ours=reached)
    # the replay alone: every plan as if it left no weld out
    from types import SimpleNamespace

    whole = tuple(None if p is None else SimpleNamespace(partial=list) for p in plans)
    clear = ReplayVerdict(True, 5.0, 12.5, (0, 4, 1, 2), 12)
    assert _exit_code(dataclasses.replace(splan, report=report, replay=clear), whole) == 0
    assert capsys.readouterr().err == ""
    close = ReplayVerdict(False, 5.0, 0.0, (0, 0, 1, 0), 12, ("robot1 at rest at row 0 ...",))
    assert _exit_code(dataclasses.replace(splan, report=report, replay=close), whole) == 3
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith("weldplan: the replay found robots too close")


# ------------------------------------------- verify re-runs the replay from the files (fast)
#: mm, deg: the bases of the crossing pair, as tests/multi_fixtures.py `pair` places them
CROSSING_BASES = ((-2000.0, 0.0, 0.0, 0.0), (2000.0, 0.0, 0.0, 180.0))


def _crossing_pair(tmp_path):
    """Two KR 150 4 m apart crossing in the middle (tests/multi_fixtures.py), each with the
    station's spot gun: ``(station, timings, plans, names, the live interference stage's
    (plans, schedule, verdict, line))``."""
    from tests import multi_fixtures as mf
    from tests.test_multi_plan import _synthetic_plan
    from weldplan import load_station
    from weldplan.multi.station import _interference
    from weldplan.station.mount import mount_tool

    robots, timings = mf.pair(distance=4000.0)  # 3 m apart the guns touch at the start
    station = load_station(_station_toml(tmp_path, ["1", "9"], bases=CROSSING_BASES))
    plans = [
        dataclasses.replace(_synthetic_plan(r, t), tool=mount_tool(spec.tool, r))
        for r, t, spec in zip(robots, timings, station.robots, strict=True)
    ]
    names = ("robot1", "robot2")
    return station, timings, plans, names, _interference(station, plans, names, {})


def _crossing_saved(tmp_path):
    """Two KR 150 4 m apart crossing in the middle (tests/multi_fixtures.py), each with the
    station's spot gun, through the live interference stage; saved as a station plan would
    record them: ``(station, SavedStationPlan, live verdict, live ReplayRobots)`` (trajectory
    CSVs in ``tmp_path``)."""
    from weldplan.io.trajectory import trajectory_csv_text
    from weldplan.multi.saved import SavedRobot, SavedStationPlan
    from weldplan.multi.station import _replay_robots

    station, timings, plans, names, (out, schedule, verdict, _) = _crossing_pair(tmp_path)
    saved_robots = []
    for k, t in enumerate(timings):
        f = tmp_path / f"route_robot{k + 1}_trajectory.csv"
        f.write_text(trajectory_csv_text(t, header=["written by the test"]))
        saved_robots.append(SavedRobot(names[k], None, CROSSING_BASES[k], (), None, f, (), t.total))
    saved = SavedStationPlan(
        tmp_path / "route_station.json", None, tuple(saved_robots), None, schedule,
        schedule.cycle_time, "", verdict,
    )  # fmt: skip
    return station, saved, verdict, _replay_robots(station, out, names)


def test_verify_re_runs_the_replay_from_the_files_and_fails_without_the_interlocks(tmp_path):
    from weldplan.multi.recheck import interference_check
    from weldplan.multi.replay import replay_station

    station, saved, live, rr = _crossing_saved(tmp_path)
    assert live.ok and saved.schedule.interlocks  # the gun's crossing needs an interlock
    check = interference_check(saved, station)
    assert check.ok and check.left_out == ()
    # the recorded distance re-found from the files (joints to 1e-8 rad in the CSV)
    found = float(re.search(r"min ([0-9.]+) mm", check.text).group(1))
    assert found == pytest.approx(live.min_distance, abs=1e-3) and found > station.clearance
    # the interlocks edited away: the re-run finds the two robots too close, against the record
    bare = dataclasses.replace(saved, schedule=dataclasses.replace(saved.schedule, interlocks=()))
    check = interference_check(bare, station)
    assert not check.ok and "robots closer than" in check.text and "recorded: ok" in check.text
    assert "robot1" in check.text and "robot2" in check.text
    # a recorded minimum distance off by more than the tolerance does not agree
    off = dataclasses.replace(live, min_distance=live.min_distance + 0.01)
    assert not interference_check(dataclasses.replace(saved, replay=off), station).ok
    # a record of robots too close that the re-run confirms: a partial plan naming the pair
    bad = dataclasses.replace(saved.replay, ok=False)
    bare_live = replay_station(rr, (), station.clearance)
    check = interference_check(dataclasses.replace(bare, replay=bare_live), station)
    assert check.ok and len(check.left_out) == 1 and "robot1" in check.left_out[0]
    assert not interference_check(dataclasses.replace(saved, replay=bad), station).ok
