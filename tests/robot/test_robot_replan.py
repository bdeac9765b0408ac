"""Blocked legs detoured in joint space, welds blocked on every branch, pedestal heights."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tests.conftest import require_shared
from tests.robot_helpers import BOX_BASE, TORCH_TCP, down_poses, make_plate
from tests.route_fixtures import box_part, box_route
from weldplan.errors import PlanningError
from weldplan.robot import load_robot
from weldplan.robot.collision import RobotCollision
from weldplan.robot.placement import BaseSearch, arm_reach, base_pose, search_base
from weldplan.robot.route import Detour, RobotRoute, plan_robot_route, subdivide
from weldplan.robot.settings import JointRouteSettings, RobotCell, ToolOnRobot
from weldplan.tool import arc_torch
from weldplan.tool.poses import weld_rows

DOWN = np.diag([1.0, -1.0, -1.0])  # TCP z pointing down


@pytest.fixture(scope="module")
def robot():
    d = require_shared("robots", "kuka_kr150r3100_2")
    return load_robot(d / "kr150r3100_2.urdf")


def test_subdivide_adds_points_on_the_polyline_only():
    P = np.array([[0.0] * 6, [1.0] + [0.0] * 5, [1.0, 3.0, 0, 0, 0, 0]])
    S = subdivide(P, 4)
    assert len(S) - 2 >= 4
    # every added point lies on a segment of P; the ends are P's
    np.testing.assert_array_equal(S[0], P[0])
    np.testing.assert_array_equal(S[-1], P[-1])
    seg_len = np.linalg.norm(np.diff(S, axis=0), axis=1).sum()
    assert seg_len == pytest.approx(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())


def test_a_blocked_joint_motion_is_replanned_around_the_plate(robot):
    """A1 sweeps the torch through a plate; the seeded rrtconnect detour is free under an
    independent dense FCL sampling of the whole tool and links, and the same seed repeats it."""
    qm = np.array([0.0, -1.2, 1.2, 0.0, 0.8, 0.0])
    qa, qb = qm.copy(), qm.copy()
    qa[0], qb[0] = -0.3, 0.3
    flange = robot.fk(qm)[0, :3, 3]
    plate = make_plate(flange, 1, size=160.0)
    chk = RobotCollision(robot, plate, arc_torch(), TORCH_TCP)
    assert not chk.motion_free(qa, qb)
    # no tucked-arm shortcut: OMPL plans it
    det = Detour(robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 10.0, 3, tuck=())
    path = det.transfer(qa, qb)
    assert path is not None and len(path) >= 3
    np.testing.assert_array_equal(path[0], qa)
    np.testing.assert_array_equal(path[-1], qb)
    assert chk.path_hits(path) == []
    for a, b in zip(path[:-1], path[1:], strict=True):
        assert all(chk.state_free(a + t * (b - a)) for t in np.linspace(0.0, 1.0, 200))
    again = det.transfer(qa, qb)
    np.testing.assert_array_equal(again, path)
    # the tucked arm (A2 -90, A3 90 deg) lifts the torch over the plate: three straight motions
    tucked = Detour(robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 10.0, 3)
    P = tucked.transfer(qa, qb)
    assert P is not None and len(P) == 4 and chk.path_hits(P) == []
    np.testing.assert_allclose(np.degrees(P[1:3, 1:3]), [[-90.0, 90.0]] * 2)


def test_a_starved_transfer_gets_one_longer_retry_within_the_route_budget(robot):
    """The first OMPL run has 3 checks, too few to solve; the retry (next seed, its own budget
    of checks) does, and a route whose retry budget is spent gets none; budgets of checks give
    the same detour on every run."""
    qm = np.array([0.0, -1.2, 1.2, 0.0, 0.8, 0.0])
    qa, qb = qm.copy(), qm.copy()
    qa[0], qb[0] = -0.3, 0.3
    plate = make_plate(robot.fk(qm)[0, :3, 3], 1, size=160.0)
    chk = RobotCollision(robot, plate, arc_torch(), TORCH_TCP)
    args = (robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 10.0, 3)
    det = Detour(*args, tuck=(), checks=3, retry_checks=5000)
    path = det.transfer(qa, qb)
    assert path is not None and chk.path_hits(path) == []
    assert det.ompl["runs"] == 2 and det.ompl["retries"] == 1 and det.ompl["solved"] == 1
    assert det.ompl["clock"] == 0 and 3 <= det.ompl["checks"] - det.ompl["retry_checks"] < 20
    again = Detour(*args, tuck=(), checks=3, retry_checks=5000)
    np.testing.assert_array_equal(again.transfer(qa, qb), path)
    assert again.ompl["checks"] == det.ompl["checks"]
    spent = Detour(*args, tuck=(), checks=3, retry_checks=5000, retry_total_checks=0)
    assert spent.transfer(qa, qb) is None
    assert spent.ompl["runs"] == 1 and spent.ompl["solved"] == 0


def test_one_leg_takes_at_most_its_share_of_the_route_retries(robot):
    """A leg's retries get at most ``retry_leg_checks`` of the route's retry checks, and never
    more than the route has left: a leg no run can join leaves the rest to the legs after it."""
    qm = np.array([0.0, -1.2, 1.2, 0.0, 0.8, 0.0])
    qa, qb = qm.copy(), qm.copy()
    qa[0], qb[0] = -0.3, 0.3
    plate = make_plate(robot.fk(qm)[0, :3, 3], 1, size=160.0)
    chk = RobotCollision(robot, plate, arc_torch(), TORCH_TCP)
    args = (robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 10.0, 3)
    det = Detour(*args, tuck=(), checks=2, retry_checks=2, retry_leg_checks=4,
                 retry_total_checks=100)  # fmt: skip
    assert det._run_checks(0, 0) == 2 and det._run_checks(1, 0) == 2
    assert det._run_checks(1, 3) == 1 and det._run_checks(2, 4) == 0
    det.ompl["retry_checks"] = 99.0
    assert det._run_checks(1, 0) == 1


def test_each_retry_of_a_leg_gets_twice_the_last_ones_checks(robot):
    """Retry k of one transfer runs ``retry_checks`` x 2^(k - 1) checks (a fresh seed, twice the
    work), cut to what is left of the leg's and the route's retry budgets."""
    chk = RobotCollision(robot, make_plate(np.zeros(3), 1, size=10.0), arc_torch(), TORCH_TCP)
    args = (robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 10.0, 3)
    det = Detour(*args, checks=5, retry_checks=10, retry_leg_checks=60, retry_total_checks=100)
    assert [det._run_checks(k, 0) for k in range(4)] == [5, 10, 20, 40]
    assert det._run_checks(3, 10 + 20) == 30  # the leg has 30 left
    det.ompl["retry_checks"] = 95.0
    assert det._run_checks(2, 0) == 5  # the route has 5 left


def test_a_transfer_keeps_its_ends_ik_branch(robot):
    """Arm reaching back over its shoulder (elbow and shoulder bits set, branch 3), A1 sweeping
    the torch through a plate: the tucked arm (A3 at +90 deg) would pass it by flipping the
    elbow and the shoulder; a transfer that keeps the branch refuses that and OMPL plans a path
    on branch 3, judged by IK of FK (``branch_of``) every 2 % of every motion."""
    qm = np.array([0.0, -1.9, -0.4, 0.0, 0.8, 0.0])
    qa, qb = qm.copy(), qm.copy()
    qa[0], qb[0] = -0.3, 0.3
    assert robot.branch_of(np.array([qa, qb])).tolist() == [3, 3]
    plate = make_plate(robot.fk(qm)[0, :3, 3], 1, size=160.0)
    chk = RobotCollision(robot, plate, arc_torch(), TORCH_TCP)
    assert not chk.motion_free(qa, qb)
    t = np.linspace(0.0, 1.0, 51)[:, None]

    def branches(P):
        D = [a + t * (b - a) for a, b in zip(P[:-1], P[1:], strict=True)]
        return set(robot.branch_of(np.vstack(D)))

    args = (robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 10.0, 3)
    flips = Detour(*args, keep_branch=False).transfer(qa, qb)
    assert flips is not None and branches(flips) > {3}  # the tuck: through other branches
    det = Detour(*args)
    kept = det.transfer(qa, qb)
    assert kept is not None and branches(kept) == {3} and chk.path_hits(kept) == []
    assert det.ompl["solved"] == 1
    # a motion across A5 = 0 leaves the wrist's branch
    qf = qa.copy()
    qf[4] = -0.8
    assert det.on_branch(qa, qb, 3) and not det.on_branch(qa, qf, 3)


def test_a_weld_blocked_on_every_branch_is_reported_with_its_link(robot):
    """A plate across the flange's place at weld B: every branch puts the wrist there."""
    route = box_route()
    poses = down_poses(route)
    B = route.joint_xyz[route.joint_ids.index("B")]
    flange_b = B + [0.0, 0.0, 425.0 + 40.0]  # 40 mm above the flange face: inside link_6's reach
    part = trimesh.util.concatenate([box_part(), make_plate(flange_b, 2, size=120.0)])
    rr = plan_robot_route(
        route,
        poses,
        robot,
        tool=ToolOnRobot(TORCH_TCP, arc_torch()),
        cell=RobotCell(part, base=BOX_BASE),
        settings=JointRouteSettings(replan=False),
    )
    k = rr.weld_ids.index("B")
    assert rr.status[k] == "collision"
    assert rr.detail[k].startswith("link_") and "every usable branch" in rr.detail[k]
    # the body it names does touch the part on every usable branch at that pose
    rb = robot.with_base(BOX_BASE)
    sol = rb.ik(np.block([[DOWN, B[:, None]], [np.zeros((1, 3)), 1.0]]) @ np.linalg.inv(TORCH_TCP))
    chk = RobotCollision(rb, part, arc_torch(), TORCH_TCP)
    assert len(sol) > 0 and not any(chk.state_free(q, zone=True) for q in sol.q)
    # B is not welded: no exact row stands for it
    assert not rr.exact[rr.row == weld_rows(route)[k]].any()
    assert RobotRoute.from_json(rr.to_json()).detail == rr.detail


def test_base_search_climbs_a_pedestal_when_the_floor_is_too_low(robot):
    """Welds so high that no floor base reaches them: the search takes the pedestal height."""
    H = arm_reach(robot) + 100.0  # TCP height: the wrist centre is c4 + 425 mm above it
    xyz = np.array([[0.0, 0.0, H], [120.0, 0.0, H], [0.0, 120.0, H]])
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, :3, :3] = DOWN
    T[:, :3, 3] = xyz
    T_fl = T @ np.linalg.inv(TORCH_TCP)
    with pytest.raises(PlanningError):
        search_base(robot, T_fl, None, BaseSearch(floor_z=0.0, heights=(0.0,)))
    pl = search_base(robot, T_fl, None, BaseSearch(floor_z=0.0, heights=(0.0, 800.0)))[0]
    assert pl.n_usable == 3
    assert pl.xyz_yaw()[2] == pytest.approx(800.0)
    with pytest.raises(ValueError, match="heights"):
        BaseSearch(heights=(-5.0,))


def test_sight_clear_sees_a_wall_between_the_shoulder_and_the_wrist(robot):
    from weldplan.geometry.distance import SurfaceDistance
    from weldplan.robot.placement import sight_clear

    T = np.eye(4)[None].copy()
    T[0, :3, :3] = DOWN
    T[0, :3, 3] = [2000.0, 0.0, 1500.0]  # flange pose; wrist centre 215 mm above it
    bases = np.array([base_pose(0.0, 0.0, 0.0, 0.0), base_pose(0.0, 0.0, 0.0, 90.0)])
    wall = make_plate([1000.0, 0.0, 1000.0], 0, size=600.0)  # across the chord, x = 1000
    aside = make_plate([1000.0, 2000.0, 1000.0], 0, size=600.0)
    assert not sight_clear(robot, bases, T, SurfaceDistance(wall)).any()
    assert sight_clear(robot, bases, T, SurfaceDistance(aside)).all()
