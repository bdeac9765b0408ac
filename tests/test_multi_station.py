"""Allocation on real models (weldplan.multi.inputs): the demo part, the shared spot gun, two
KUKA KR 150 at given bases on either side of the part. The study's reach and the leg times of
weldplan.robot.route.legtime go into the allocation; the exact optimum over those times (brute force
of tests/test_multi_allocation.py) checks the answer and the bound."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.conftest import require_shared
from tests.test_multi_allocation import GAP, cycle_of, exact_optimum
from weldplan.io.joints import Joints, read_joints
from weldplan.io.mesh import load_part

ROOT = Path(__file__).resolve().parents[1]
#: demo welds of the station (15: A2 past its limit from both bases)
IDS = ("1", "3", "5", "7", "9", "11", "13", "15")
#: (x, y, z mm, yaw deg) in the part frame: behind the part facing it, and in front facing back
BASES = ((448.1, 95.3, 652.7, -7.5), (2450.0, -150.0, 652.7, 180.0))
WELD_TIME = (0.5, 0.6)


@pytest.fixture(scope="module")
def station():
    from weldplan.multi.inputs import study_inputs
    from weldplan.robot import load_robot
    from weldplan.robot.placement import base_pose
    from weldplan.study import StudyRobot, check_spots, load_study_tool

    gun_path = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    j = read_joints(ROOT / "assets" / "demo" / "joints.csv")
    k = [j.ids.index(i) for i in IDS]
    spots = Joints(ids=IDS, xyz=np.asarray(j.xyz)[k], directions=np.asarray(j.directions)[k])
    gun = load_study_tool(str(gun_path), tcp="nozzle_tip", name="gun")
    robots = [load_robot(urdf, base=base_pose(*b)) for b in BASES]
    part = load_part(ROOT / "assets" / "demo" / "part.stl")
    study = check_spots(
        part, spots, [gun], [StudyRobot(f"kr150_{n}", r) for n, r in zip("ab", robots, strict=True)]
    )
    return study, robots, gun, study_inputs(study, robots, WELD_TIME)


def test_the_reach_is_the_study_and_the_unreached_weld_says_why(station):
    study, _, _, inp = station
    assert np.array_equal(inp.reach.ok, study.reach_matrix().T)
    assert inp.reach.welds == IDS
    assert not inp.reach.ok[:, IDS.index("15")].any()
    assert all("joint_limit" in inp.reach.reasons[r][IDS.index("15")] for r in range(2))
    assert inp.reach.ok.sum() >= 10  # both robots serve most welds


def test_leg_times_bound_the_studys_own_configurations(station):
    """The leg time between the study's configurations is one the robot can take: never
    below the bound over every configuration; the station-branch cost never below either."""
    from weldplan.robot.route import rest_to_rest_bound

    study, robots, gun, inp = station
    for r, robot in enumerate(robots):
        idx = np.flatnonzero(inp.reach.ok[r])
        q = np.array([study.spots[i].robots[r].q for i in idx])
        own = rest_to_rest_bound(q[:, None] - q[None], robot.velocity, robot.acceleration)
        B = inp.bound[r][np.ix_(idx, idx)]
        assert np.all(B <= own + 1e-9)
        assert np.all(inp.cost[r][np.ix_(idx, idx)] >= B - 1e-9)
        # the configuration puts the gun's TCP on the spot (FK, independent of the IK)
        placed = robot.with_base(study.robots[r].base_matrix())
        tcp = placed.fk(q) @ gun.flange_tcp(robot)
        pos = np.array([study.spots[i].position for i in idx])
        assert np.allclose(tcp[:, :3, 3], pos, atol=1e-3)


def test_allocation_on_real_leg_times_against_the_exact_optimum(station):
    from weldplan.multi import allocation_report

    _, _, _, inp = station
    served = np.flatnonzero(inp.reach.ok.any(axis=0))
    rep = allocation_report(inp.reach, inp.weld_time, inp.cost, rng=0, bound_travel=inp.bound)
    ours = rep.ours
    assert [u.weld for u in ours.unreached] == ["15"]
    assert sorted(i for s in ours.shares for i in s.order) == list(served)
    assert ours.cycle_time == pytest.approx(cycle_of(ours, inp.weld_time, inp.cost, False))
    sub = type(inp.reach).of(inp.reach.ok[:, served])
    exact = exact_optimum(sub, inp.weld_time[:, served], inp.cost[:, served][:, :, served], False)
    assert exact - 1e-9 <= ours.cycle_time <= exact * (1 + GAP)
    assert rep.bound.value <= exact + 1e-9
    assert ours.cycle_time < rep.one_robot.cycle_time  # two robots beat one
    assert all(u > 0 for u in ours.utilisation)
