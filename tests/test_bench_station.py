"""``weldplan bench station`` (weldplan.bench.station): the figures are the allocation report's,
the stage clock attributes CPU to the stages a station's plan reports, the page says what was
not checked; slow: the bench end to end on a two-robot demo station file with its page and Gantt
chart."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import require_shared
from weldplan.bench import station as bs

ROOT = Path(__file__).resolve().parents[1]


def test_a_synthetic_row_carries_the_allocation_reports_figures():
    from weldplan.multi import allocation_report

    row = bs.synthetic_row(20, 2, 0)
    rep = allocation_report(*bs.synthetic_station(20, 2, 0), rng=0)
    assert (row.welds, row.robots, row.kind) == (20, 2, "allocation only")
    assert row.ours == pytest.approx(rep.ours.cycle_time, abs=1e-3)
    assert row.bound == pytest.approx(rep.bound.value, abs=1e-3)
    assert row.nearest == pytest.approx(rep.nearest.cycle_time, abs=1e-3)
    # no synthetic robot reaches every weld here: no one-robot baseline, said as such
    assert rep.one_robot is None and row.one_robot is None
    assert row.bound <= row.ours + 1e-9
    assert row.timed is None and row.replay_ok is None


def test_the_synthetic_option_is_checked():
    assert bs.parse_synthetic("100:2,400:4") == ((100, 2), (400, 4))
    for bad in ("100", "100:5", "0:2", "a:b"):
        with pytest.raises(argparse.ArgumentTypeError):
            bs.parse_synthetic(bad)


def test_the_clock_gives_each_phase_of_a_station_plan_its_cpu():
    clock = bs._StationClock()
    events = [("study", 0, 2), ("study", 1, 2), ("study", 2, 2), ("allocation", 0, 3)]
    for rnd, robots in enumerate(((1, 2), (1,))):  # round 2 re-plans robot 1's new share
        if rnd:
            events.append(("allocation", rnd, 3))
        events.append(("plan", 0, len(robots)))
        for n, r in enumerate(robots, 1):  # each share's stages, named with its robot
            for stage in ("cell", "route", "robot", "program"):
                events += [(f"robot{r} {stage}", 0, 1), (f"robot{r} local", 3, 10),
                           (f"robot{r} {stage}", 1, 1)]  # fmt: skip
            events.append(("plan", n, len(robots)))
    events.append(("interference", 0, 2))
    for e in events:
        sum(k * k for k in range(20000))  # some CPU in every phase
        clock(*e)
    sum(k * k for k in range(20000))  # the interference, after the last share
    cpu = clock.finish()
    phases = ("cell", "study robot1", "study robot2", "allocation", "shares", "interference")
    assert set(cpu) == set(phases)
    assert all(cpu[k] >= 0.0 for k in phases)
    # the phases cover the whole run: their sum is the CPU from start to finish
    assert sum(cpu[k] for k in phases) == pytest.approx(bs._cpu() - clock.t0, abs=0.05)


def test_the_jobs_option_is_checked():
    assert bs._jobs("2") == 2
    for bad in ("0", "-1", "x"):
        with pytest.raises(argparse.ArgumentTypeError):
            bs._jobs(bad)


def test_the_page_puts_the_figures_side_by_side_and_says_what_was_not_checked():
    row = bs.StationRow(
        "st", "planned", 15, 2, 1, 5.5, 3.6, 2.2, 2.0, "LP", timed=2.6, waiting=0.4,
        interlocks=1, robots_rows=(("robot1", 7, 2.2, 2.6, 0.9, 0.0),),
        wall_s={"cell": 1.0}, cpu_s={"cell": 0.9}, load=(1.0, 1.0, 1.0),
        rounds=((2.0, 3.1, (0, 1)), (2.2, 2.6, (0,))),
        baselines=(("one-robot", 5.5, 6.5), ("nearest-robot", 3.6, 3.25), ("ours", 2.2, 2.6)),
    )  # fmt: skip
    page = bs.format_page([row], "weldplan bench station", "vm")
    # the baselines planned and timed beside their modelled cycles, ours timed against each
    assert "| nearest-robot | 3.60 | 3.25 | -20.0 % |" in page
    assert "| one-robot | 5.50 | 6.50 | -60.0 % |" in page and "| ours | 2.20 | 2.60 | - |" in page
    line = next(x for x in page.splitlines() if x.startswith("| st |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[5:11] == ["5.50", "3.60", "2.20", "2.00", "+10.0 %", "-38.9 %"]
    assert cells[11:17] == ["2.60", "0.40", "1", "not checked", "2.00 / 3.10", "2"]
    assert "| 2 | 2.20 | 2.60 | robot1 |" in page  # the rounds: the second re-planned robot1
    assert "| robot1 | 7 | 2.20 | 2.60 | 90% | 0.00 |" in page
    assert "| cell | 1.00 | 0.90 |" in page


@pytest.mark.slow
def test_the_bench_plans_a_two_robot_station_file_and_draws_it(tmp_path):
    import weldplan
    from tests.conftest import require_shared
    from weldplan.io.joints import Joints, read_joints
    from weldplan.weld import demo_part

    data = require_shared()
    ids = ("1", "5", "7", "9", "13", "15")
    j = read_joints(demo_part.DEMO_JOINTS)
    k = [j.ids.index(i) for i in ids]
    Joints(ids=ids, xyz=np.asarray(j.xyz)[k], directions=np.asarray(j.directions)[k]).to_csv(
        tmp_path / "welds.csv"
    )
    robots = "".join(
        f"""
[[robot]]
urdf = "{data}/robots/kuka_kr150r3100_2/kr150r3100_2.urdf"
weld_time = 0.5
base = {list(b)}
home = {list(bs.DEMO_HOME)}
[robot.tool]
file = "{data}/tools/spot_welding_gun/spot_welding_gun.urdf"
"""
        for b in bs.DEMO_BASES
    )
    toml = tmp_path / "two.toml"
    toml.write_text(
        f'seed = 0\n[part]\nmesh = "{demo_part.DEMO_PART}"\nwelds = "{tmp_path / "welds.csv"}"\n'
        '[route]\nplanner = "exact"\n' + robots
    )
    out = tmp_path / "out"
    args = argparse.Namespace(out=str(out), station=[str(toml)], no_demo=True, synthetic=(),
                              seed=0, pages=True, plan_baselines=True)  # fmt: skip
    assert bs.run(args) == 0
    page = (out / "station.md").read_text()
    row = next(x for x in page.splitlines() if x.startswith("| two |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells[1:4] == ["planned", "6", "2"]
    assert float(cells[7]) >= float(cells[8])  # ours >= bound
    # the baselines planned and timed: ours timed is the kept round's, as the station JSON
    # records it; the nearest split timed, and every timed cycle above the bound
    (got,) = json.loads((out / "station.json").read_text())
    saved = weldplan.load_station_plan(out / "two_station.json")
    # the unreached: weld 15 (no robot reaches it) and any a failed share gave up, as recorded
    un = [u.weld for u in saved.report.ours.unreached]
    assert "15" in un and cells[4] == str(len(un))
    names = [b[0] for b in got["baselines"]]
    assert names[-1] == "ours" and "nearest-robot" in names
    assert got["baselines"][-1][2] == pytest.approx(
        saved.rounds[saved.kept_round].timed_cycle, abs=1e-3
    )
    assert all(b[2] >= got["bound"] - 1e-9 for b in got["baselines"])
    assert "Baselines planned and timed" in page and "--plan-baselines" in page
    html = (out / "two.html").read_text()
    assert "weldplan-gantt" in html and "robot2" in html
    assert (out / "two_gantt.png").read_bytes().startswith(b"\x89PNG")


def test_the_bench_stations_read_as_two_robots_at_given_bases():
    import weldplan

    require_shared("robots")  # the stations name the shared KR 150 and gun
    demo = bs.demo_two_robots()
    assert [r.base for r in demo.robots] == list(bs.DEMO_BASES)
    assert demo.part.welds.name == "joints.csv"
    car2 = weldplan.load_station(ROOT / "examples" / "car2_two_robots.toml")
    assert len(car2.robots) == 2 and all(r.base is not None for r in car2.robots)
    assert {r.tool.builtin for r in car2.robots} == {"arc_torch"}
    assert car2.part.welds.name == "car2_synthetic_200.csv" and car2.part_pose is None


def test_the_car2_stations_stand_the_body_upright_with_two_and_four_robots_apart():
    import weldplan
    from weldplan.multi.cell import check_apart
    from weldplan.robot import load_robot
    from weldplan.robot.placement.reach import base_pose

    require_shared("bodies", "car2.obj")
    sizes = []
    for f in bs.CAR2_STATIONS:
        st = weldplan.load_station(ROOT / "examples" / f)
        # on its wheels: the part's y turned to the cell's z, its lowest point 500 mm up
        assert st.part_pose is not None and st.part_pose.fixture_z == 500.0
        np.testing.assert_array_equal(st.part_pose.matrix[:3, 2], [0.0, -1.0, 0.0])
        assert {r.tool.builtin for r in st.robots} == {"arc_torch"}
        assert all(r.tool.params["bend_angle"] == 0.0 for r in st.robots)
        # every base given, standing on the floor, the footprints clear of each other
        assert all(r.base is not None and r.base[2] == 0.0 for r in st.robots)
        robots = [(r, None, load_robot(r.urdf, r.opw, base=base_pose(*r.base))) for r in st.robots]
        check_apart(robots)
        sizes.append((len(st.robots), sum(1 for _ in open(st.part.welds)) - 2))
    assert sizes == [(2, 200), (4, 400)]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["car2_two_robots", "car2_upright_200_2", "car2_upright_400_4"])
def test_the_example_stations_give_every_robot_a_home_clear_of_the_part_and_the_others(name):
    """The check ``weldplan plan`` runs before any study (:func:`weldplan.multi.station.with_homes`:
    each home inside the limits, the robot at it clear of the part, the floor and itself, the
    robots at their homes apart) accepts every example station as the file gives it."""
    import weldplan
    from weldplan.multi import station as ms
    from weldplan.station.pipeline import cell_stage

    require_shared("bodies", "car2.obj")
    st = weldplan.load_station(ROOT / "examples" / f"{name}.toml")
    assert all(r.settings.home is not None for r in st.robots)
    robots = ms._robots(st)
    homed = ms.with_homes(st, cell_stage(st), robots)
    assert [r.settings.home for r in homed.robots] == [r.settings.home for r in st.robots]
