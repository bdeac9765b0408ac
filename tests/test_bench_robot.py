"""``weldplan bench robot``: its options, the per-seed / per-base runs and their rows."""

from __future__ import annotations

import argparse
import json

import pytest
from conftest import require_shared
from route_fixtures import write_box_station

from weldplan.bench import robot as bench
from weldplan.bench import robot_runs


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser()
    bench.add_arguments(p)
    return p


@pytest.mark.parametrize(
    "text, seeds",
    [("0-4", (0, 1, 2, 3, 4)), ("3", (3,)), ("0,3,7", (0, 3, 7)), ("1-3,2-5", (1, 2, 3, 4, 5))],
)
def test_seeds_are_ranges_or_lists(text, seeds):
    assert bench.parse_seeds(text) == seeds


@pytest.mark.parametrize("text", ["4-0", "-1", "a", "", "1-", "0-2,x"])
def test_bad_seeds_are_refused(text):
    with pytest.raises(argparse.ArgumentTypeError, match="seeds must be"):
        bench.parse_seeds(text)


def test_the_options_parse_as_the_issue_writes_them():
    args = _parser().parse_args(
        ["-n", "50", "--tool", "torch", "--up", "y", "--seeds", "0-4",
         "--yaw-offsets=-30,-15,15,30"]
    )  # fmt: skip
    assert args.seeds == (0, 1, 2, 3, 4) and args.yaw_offsets == (-30.0, -15.0, 15.0, 30.0)
    assert args.up == "y" and args.tool == "torch" and args.n == 50
    one = _parser().parse_args(["--station", "s.toml"])
    assert one.station == "s.toml" and one.seeds is None and one.yaw_offsets == ()
    for bad in (["--yaw-offsets=15,x"], ["--yaw-offsets=15,15"], ["--yaw-offsets=200"],
                ["--up", "w"]):  # fmt: skip
        with pytest.raises(SystemExit):
            _parser().parse_args(bad)


def test_the_trial_clock_takes_the_robot_stages_seconds_at_the_trials_line():
    """The row's ``said_at``: seconds from the robot stage's start to the walk's trial line;
    none before the robot stage starts, the first line only, other lines ignored."""
    import logging

    clock = robot_runs._StageClock()
    said = robot_runs._TrialClock(clock)

    def line(msg):
        return logging.LogRecord("weldplan.robot.route.walk", 30, "", 0, msg, (), None)

    said.emit(line("robot walk: the transfer trial on the route at this base: ..."))
    assert said.at is None  # the robot stage has not started
    clock("robot", 0, 1)
    said.emit(line("weld W1 dropped: ..."))
    assert said.at is None
    said.emit(line("robot walk: the transfer trial on the route at this base: ..."))
    first = said.at
    assert first is not None and all(0.0 <= v < 60.0 for v in first)
    said.emit(line("robot walk: the transfer trial on the route at this base: again"))
    assert said.at is first
    assert robot_runs._walk_cell({"detours": 2, "split_legs": ["a", "b"]}, (3.14, 9.0)).endswith(
        "; 2 split at 3 s"
    )


def test_a_turned_base_keeps_its_place_and_wraps_its_yaw(tmp_path):
    from weldplan.station import model as m

    _, mesh, joints = write_box_station(tmp_path)
    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    tool = m.ToolSpec(builtin="arc_torch", params={"bend_angle": 0.0}, mass=5.0)
    st = m.Station(
        part=m.PartSpec(mesh, joints), robots=(m.RobotSpec(tool=tool, urdf=urdf, search={}),)
    )
    t = robot_runs.turned(st, (10.0, -20.0, 30.0, 170.0), 30.0)
    (r,) = t.robots
    assert r.base == (10.0, -20.0, 30.0, -160.0) and r.search == {}
    assert robot_runs.turned(st, (0, 0, 0, -170.0), -15.0).robots[0].base[3] == 175.0
    assert t.part == st.part and t.tool == st.tool and r.tool == tool


def test_car2_upright_is_the_y_up_pose():
    from weldplan.cellframe import PartPose

    require_shared("bodies", "car2.obj")
    st = bench.car2_station(50, "torch", up="y")
    assert st.part_pose is not None and st.part_pose.same_as(PartPose.from_up("y"))
    assert bench.car2_station(50, "torch").part_pose is None


def _box_torch(tmp_path):
    """The box station with the bent torch on the KUKA at a given base (tests/test_station.py's)."""
    _, mesh, joints = write_box_station(tmp_path)
    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    toml = tmp_path / "box.toml"
    toml.write_text(
        f'clearance = 5.0\n[part]\nmesh = "{mesh.name}"\nwelds = "{joints.name}"\n'
        f"[cell]\nmargin = 50\n[[robot]]\nurdf = '{urdf}'\nbase = [-1800, 0, -700, 0]\n"
        "weld_time = 0.4\n[robot.tool]\nbuiltin = 'arc_torch'\nbend_angle = 22\nmass = 3\n"
    )
    return toml


def test_one_run_is_one_row_of_the_pipeline_with_cpu_per_stage(tmp_path, capsys):
    """A tiny run (4 welds, about 20 s on a loaded 2-core box): every weld in the program and
    reachable at the given base, the robot route re-checks ok, every stage has its wall and CPU
    seconds, and the table and the JSON files say the same."""
    toml = _box_torch(tmp_path)
    out = tmp_path / "out"
    args = _parser().parse_args(["--station", str(toml), "--json"])
    args.out = str(out)
    assert bench.run(args) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert (row["in_program"], row["reachable"], row["total"]) == (4, 4, 4)
    assert row["flips"] == 0 and row["verified"] == "ok" and row["note"] == ""
    assert row["base"] == [-1800.0, 0.0, -700.0, 0.0] and not row["searched"]
    stages = ["cell", "route", "verify", "reach", "poses", "transitions", "robot", "program"]
    assert list(row["wall_s"]) == stages and set(row["cpu_s"]) >= set(stages[3:])
    assert all(v >= 0 for v in row["cpu_s"].values()) and row["cpu_total"] > 0
    table = (out / "box.md").read_text()
    assert "| seed 0, base | -1800.0, 0.0, -700.0, 0.0 | 4 / 4 / 4 | 0 | ok |" in table
    assert json.loads((out / "box.json").read_text()) == [row]


def test_a_run_whose_plan_fails_is_a_row_with_its_error(tmp_path):
    """Far from the box (a base 4 m away) the robot reaches none of the chosen poses: the plan
    fails, and the row says so with 0 / 0 / 4 and the error, not a traceback."""
    toml = _box_torch(tmp_path)
    toml.write_text(toml.read_text().replace("[-1800, 0, -700, 0]", "[-6000, 0, -700, 0]"))
    import weldplan

    (row,) = robot_runs.run_all(weldplan.load_station(toml), (0,))
    assert (row.in_program, row.reachable, row.total) == (0, 0, 4)
    assert row.note.startswith("error: ") and row.verified == "-"


@pytest.mark.slow
def test_the_seed_0_base_turned_by_zero_gives_the_same_program(tmp_path):
    """Seed 0 and the seed-0 base turned by 0 deg are the same station and seed: the same
    digest as each other and as :func:`weldplan.plan` run apart (about 60 s)."""
    import weldplan

    station = weldplan.load_station(_box_torch(tmp_path))
    rows = robot_runs.run_all(station, (0,), (0.0,))
    assert [r.label for r in rows] == ["seed 0, base", "seed-0 base +0 deg"]
    a, b = rows
    assert a.digest == b.digest == robot_runs._digest(weldplan.plan(station, rng=0))
    assert a.base == b.base and (a.in_program, a.reachable) == (b.in_program, b.reachable)
