"""The pose-free leg bounds of a station (weldplan.multi.bound.pose_free_legs) and the bound
through each robot's home (lower_bound(..., home=)), against independent answers: forward
kinematics of random configurations, toppra's timing of motions between them, brute force over
every assignment and order of a small station, and the timed legs of a planned robot."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest

from tests.robot_fixtures import gun_tcp, shared_robot


def test_axis_one_is_where_the_sets_say_for_any_configuration():
    """For 4000 random configurations of the KR 150 with the spot gun, axis 1 lies in the set
    :func:`axis_one_sets` gives for the TCP position they reach (forward kinematics only)."""
    from weldplan.multi.bound import _pi_distance, axis_one_sets

    robot = shared_robot()
    F, _ = gun_tcp(robot)
    q = np.random.default_rng(0).uniform(robot.lower, robot.upper, (4000, 6))
    p = (robot.fk(q) @ F)[:, :3, 3]
    centre, half, _ = axis_one_sets(robot, F, p)
    assert np.all(_pi_distance(q[:, 0] - centre) <= half + 1e-9)
    assert np.median(half) < np.radians(60)  # and the sets are not the whole circle


def _timed(robot, q):
    from weldplan.robot.program import time_route

    return time_route(q, robot.velocity, robot.acceleration, weld_rows=[]).total


def test_the_pose_free_legs_are_below_toppra_between_any_configurations():
    """Random configuration pairs (TCP anywhere, any gun pose, any branch) and a home: toppra's
    time of the straight joint move between them is never below the leg bounds, welds to
    welds and home to weld; and axis 1's turn makes the home legs of an arm turned away from
    the welds well above the TCP's distance alone."""
    from weldplan.multi.bound import lever_arms, pose_free_legs, tcp_leg_bound

    robot = shared_robot()
    F, _ = gun_tcp(robot)
    g = np.random.default_rng(3)
    home = np.array([np.pi / 2, -np.pi / 2, np.pi / 2, 0.0, 0.0, 0.0])
    for _ in range(8):
        q = g.uniform(robot.lower, robot.upper, (2, 6))
        p = (robot.fk(q) @ F)[:, :3, 3]
        legs = pose_free_legs(robot, F, p, home)
        assert legs.travel[0, 1] <= _timed(robot, q) + 1e-9
        for k in range(2):
            assert legs.home[k] <= _timed(robot, np.vstack([home, q[k]])) + 1e-9
    # welds in front of the robot (A1 near 0), home turned a quarter away
    q = np.array([[0.1, -1.2, 1.4, 0.0, 0.8, 0.0], [-0.1, -1.3, 1.5, 0.2, 0.7, 0.0]])
    p = (robot.fk(q) @ F)[:, :3, 3]
    legs = pose_free_legs(robot, F, p, home)
    L = lever_arms(robot.opw, float(np.linalg.norm(F[:3, 3])))
    h = (robot.fk(home) @ F)[0, :3, 3]
    tcp = tcp_leg_bound(np.vstack([h, p]), L, robot.velocity, robot.acceleration)[0, 1:]
    assert np.all(legs.home > 1.5 * tcp)
    assert np.all(legs.home <= [_timed(robot, np.vstack([home, qk])) for qk in q])


def _brute_force(T, H, wt, ok):
    """The least station cycle over every assignment and every order (home -> welds ->
    home per robot, a robot with no weld: 0)."""
    R, W = ok.shape
    best = np.inf
    for assign in itertools.product(range(R), repeat=W):
        if any(not ok[r, i] for i, r in enumerate(assign)):
            continue
        cyc = 0.0
        for r in range(R):
            S = [i for i in range(W) if assign[i] == r]
            if not S:
                continue
            route = min(
                H[r, o[0]] + sum(T[r, a, b] for a, b in itertools.pairwise(o)) + H[r, o[-1]]
                for o in itertools.permutations(S)
            )
            cyc = max(cyc, route + wt[r, S].sum())
        best = min(best, cyc)
    return best


@pytest.mark.parametrize("seed", range(6))
def test_the_bound_through_the_homes_is_below_the_optimum_of_small_stations(seed):
    """Two or three robots, six welds, random asymmetric move times and home legs: the bound
    with homes is never above the brute-force optimum, and with far homes it is above the
    bound without them."""
    from weldplan.multi.bound import lower_bound
    from weldplan.multi.problem import AllocationProblem

    g = np.random.default_rng(seed)
    R, W = 2 + seed % 2, 6
    ok = g.random((R, W)) < 0.7
    ok[g.integers(R, size=W), np.arange(W)] = True
    T = g.uniform(0.2, 2.0, (R, W, W))
    H = g.uniform(1.0, 3.0, (R, W))
    wt = np.full((R, W), 0.5)
    problem = AllocationProblem.build(ok, wt, T, False)
    with_home = lower_bound(problem, home=H)
    assert with_home.value <= _brute_force(T, H, wt, ok) + 1e-9
    assert with_home.value > lower_bound(problem).value
    assert "home" in with_home.name


def test_a_home_of_the_wrong_shape_is_named():
    from weldplan.errors import ConfigError
    from weldplan.multi.bound import lower_bound
    from weldplan.multi.problem import AllocationProblem

    problem = AllocationProblem.build(
        np.ones((2, 3), bool), np.zeros((2, 3)), np.ones((2, 3, 3)), False
    )
    with pytest.raises(ConfigError, match=r"must be \(2, 3\) s") as err:
        lower_bound(problem, home=np.zeros((3, 2)))
    assert err.value.field == "home"


@pytest.mark.slow
def test_every_timed_leg_of_a_planned_robot_is_above_its_pose_free_bound():
    """The demo two-robot station's first robot planned alone at its base with its home (the
    whole single-robot pipeline: gun poses, transitions, detours, toppra): every timed leg
    between two welds, and its legs out of its home and back, take at least their bound
    over the welds' TCP positions."""
    import weldplan
    from tests.conftest import require_shared
    from weldplan.bench.station import demo_two_robots
    from weldplan.multi.bound import pose_free_legs

    require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")  # the station's gun
    require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    st = demo_two_robots()
    st = dataclasses.replace(st, robots=st.robots[:1], name="demo-robot-1")
    plan = weldplan.plan(st, rng=0)
    robot, route = plan.robot.robot, plan.robot.robot_route
    tm = plan.program.timing
    rows = np.asarray(tm.weld_rows)
    assert len(rows) >= 5
    q = np.array([tm.q[np.flatnonzero(tm.step == w)[0]] for w in rows])
    F = route.flange_tcp
    p = (robot.fk(q) @ F)[:, :3, 3]
    legs = pose_free_legs(robot, F, p, np.radians(st.robots[0].settings.home))
    arrive = np.asarray(tm.row_times)[rows]
    timed = np.diff(arrive) - tm.weld_time
    bound = legs.travel[np.arange(len(rows) - 1), np.arange(1, len(rows))]
    assert np.all(bound <= timed + 1e-9)
    assert legs.home[0] <= arrive[0] + 1e-9
    assert legs.home[-1] <= tm.total - arrive[-1] - tm.weld_time + 1e-9


def test_bases_too_close_name_the_station_file_the_line_and_the_key(tmp_path, capsys):
    """Two robots 1 m apart in a station file (their footprints need 1535 mm): one line at the
    command line naming the file, the second robot's ``base`` line and ``robot.base``."""
    from tests.conftest import require_shared
    from weldplan.cli import main

    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    gun = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    root = Path(__file__).resolve().parents[1] / "assets" / "demo"
    text = f'[part]\nmesh = "{root / "part.stl"}"\nwelds = "{root / "joints.csv"}"\n'
    for y in (95.3, 1095.3):
        text += f'[[robot]]\nurdf = "{urdf}"\nbase = [448.1, {y}, 652.7, 0.0]\n'
        text += f'[robot.tool]\nfile = "{gun}"\n'

    f = tmp_path / "close.toml"
    f.write_text(text)
    line = text.splitlines().index("base = [448.1, 1095.3, 652.7, 0.0]") + 1
    assert main(["plan", str(f), "-o", str(tmp_path / "r.csv")]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    said = [e for e in err if "apart" in e]
    assert len(said) == 1 and "Traceback" not in "\n".join(err)
    assert f"{f}" in said[0] and f"line {line}" in said[0] and "robot.base" in said[0]
    assert "robots 1 and 2 stand 1000.0 mm apart" in said[0]
