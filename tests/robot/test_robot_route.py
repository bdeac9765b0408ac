"""Reach, configurations, robot collision and plan_robot_route on small hand-made scenes."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from tests.conftest import require_shared
from tests.robot_helpers import BOX_BASE, TORCH_TCP, down_poses, make_plate
from tests.route_fixtures import box_part, box_route
from weldplan.errors import InputError, PlanningError
from weldplan.robot import load_robot
from weldplan.robot.collision import RobotCollision
from weldplan.robot.model import IKBranches
from weldplan.robot.placement import (
    JOINT_LIMIT,
    OK,
    OUT_OF_REACH,
    SINGULAR,
    BaseSearch,
    base_pose,
    classify,
    may_reach,
    parse_base,
    search_base,
    usable,
)
from weldplan.robot.route import (
    RobotRoute,
    choose_configurations,
    joint_path,
    motion_cost,
    plan_robot_route,
    turn_variants,
)
from weldplan.robot.settings import JointRouteSettings, RobotCell, ToolOnRobot
from weldplan.tool import arc_torch


@pytest.fixture(scope="module")
def robot():
    d = require_shared("robots", "kuka_kr150r3100_2")
    return load_robot(d / "kr150r3100_2.urdf")


# ------------------------------------------------------------------------------ reach


def test_parse_base():
    B = parse_base("100, -50, 0, 90")
    np.testing.assert_allclose(B[:3, 3], [100, -50, 0])
    np.testing.assert_allclose(B[:3, 0], [0, 1, 0], atol=1e-12)
    for bad in ("1,2,3", "1,2,3,x", "1,2,nan,4"):
        with pytest.raises(InputError) as ei:
            parse_base(bad)
        assert ei.value.field == "--robot-base"


def test_classify_precedence():
    n = 5
    nan = np.full((n, 8), np.nan)
    exists = np.zeros((n, 8), bool)
    in_lim = np.zeros((n, 8), bool)
    wrist = nan.copy()
    exists[1:4] = True  # poses 0 and 4: no branch at all
    wrist[1:4] = 0.5
    in_lim[2:4] = True  # pose 1: branches, none in limits
    wrist[2] = 0.01  # pose 2: in limits but at the wrist singularity
    ext = np.array([-5.0, 1.0, 1.0, 1.0, 3.0])  # pose 4: wrist centre in reach, no branch
    br = IKBranches(np.zeros((n, 8, 6)), exists, in_lim, nan, wrist, ext)
    assert classify(br, 5.0).tolist() == [OUT_OF_REACH, JOINT_LIMIT, SINGULAR, OK, SINGULAR]
    assert classify(br, 0.1).tolist()[2] == OK  # 0.1 deg threshold: sin > 0.00175


def test_real_poses_get_their_reason(robot):
    far = np.eye(4)
    far[:3, 3] = [4000.0, 0.0, 700.0]
    near_sing = robot.fk([0.2, -1.2, 1.0, 0.3, 0.01, 0.4])[0]  # A5 = 0.57 deg
    exact_sing = robot.fk([0.2, -1.2, 1.0, 0.3, 0.0, 0.4])[0]
    br = robot.ik_all(np.stack([far, near_sing, exact_sing]))
    assert classify(br, 5.0).tolist() == [OUT_OF_REACH, OK, OK]  # other branches do it
    u = usable(br, 5.0)
    assert not u[0].any()
    # the two branches with A5 = +-0.01 (wrist flip twins) are the ones left out
    small = np.abs(np.nan_to_num(br.q[1, :, 4], nan=1.0)) < 0.011
    assert small.sum() == 2 and not u[1, small].any() and u[1, ~small & br.in_limits[1]].all()
    assert u[2].sum() == u[1].sum()


def test_may_reach_rules_out_only_poses_without_a_branch(robot):
    rng = np.random.default_rng(7)
    T = np.tile(np.eye(4), (20_000, 1, 1))
    T[:, :3, :3] = Rotation.random(len(T), random_state=rng).as_matrix()
    T[:, :3, 3] = rng.uniform([-4500.0, -4500.0, -3000.0], [4500.0, 4500.0, 4500.0], (len(T), 3))
    at0 = robot.with_base(np.eye(4))
    maybe = may_reach(at0, T)
    br = at0.ik_all(T)
    assert not br.exists[~maybe].any()  # sound: nothing it rules out has a branch
    assert br.extension[~maybe].max() < -0.99  # every one lies beyond the reach and the slack
    assert 0.3 < np.mean(~maybe) and br.exists[maybe].any(axis=1).mean() > 0.5  # and it bites


# ------------------------------------------------------------------------------ configs


def test_dp_is_the_exact_shortest_path():
    rng = np.random.default_rng(5)
    m, K = 5, 4
    Q = rng.uniform(-2, 2, (m, K, 6))
    branch = rng.integers(0, 3, (m, K))
    valid = rng.random((m, K)) < 0.8
    valid[:, 0] = True
    v = np.array([1.0, 1.0, 1.2, 2.0, 2.0, 3.0])
    pen = 0.7
    choice = choose_configurations(Q, branch, valid, v, flip_penalty=pen)

    def cost(c):
        tot = 0.0
        for i in range(1, m):
            tot += motion_cost(Q[i - 1, c[i - 1]][None], Q[i, c[i]][None], v)[0, 0]
            tot += pen * (branch[i - 1, c[i - 1]] != branch[i, c[i]])
        return tot

    best = min(
        cost(c)
        for c in itertools.product(range(K), repeat=m)
        if all(valid[i, c[i]] for i in range(m))
    )
    assert all(valid[i, choice[i]] for i in range(m))
    assert cost(choice) == pytest.approx(best, abs=1e-12)


def test_turn_variants_add_full_turns_inside_the_limits(robot):
    q = np.array([0.1, -1.0, 1.0, 3.0, 1.0, -0.5])  # A4 at 172 deg: 172 - 360 is inside too
    br = robot.ik_all(robot.fk(q))
    Q, brn, valid = turn_variants(br, robot.lower, robot.upper, br.in_limits)
    Qv = Q[0, valid[0]]
    assert robot.in_limits(Qv).all()
    d = np.abs(Qv - q).max(axis=1)
    assert (d < 1e-9).any()
    alt = q.copy()
    alt[3] -= 2 * math.pi
    assert (np.abs(Qv - alt).max(axis=1) < 1e-9).any()
    # each variant keeps its branch label
    np.testing.assert_array_equal(robot.branch_of(Qv), brn[0, valid[0]])


def test_joint_path_along_a_line_keeps_one_branch(robot):
    q0 = np.array([0.3, -1.3, 1.4, 0.4, 0.9, -0.3])
    T0 = robot.fk(q0)[0]
    T = np.repeat(T0[None], 40, axis=0)
    T[:, :3, 3] += np.linspace(0, 400.0, 40)[:, None] * [0.0, 1.0, 0.0]
    q, branch, exact, status = joint_path(robot, T)
    assert exact.all() and (status == OK).all()
    assert len(set(branch.tolist())) == 1
    np.testing.assert_allclose(robot.fk(q), T, atol=1e-6)
    assert np.abs(np.diff(q, axis=0)).max() < 0.1  # 10 mm steps: small joint steps
    # no other single branch does the line with less joint motion
    br = robot.ik_all(T)
    mine = sum(motion_cost(q[i - 1][None], q[i][None], robot.velocity)[0, 0] for i in range(1, 40))
    for b in range(8):
        if br.in_limits[:, b].all() and b != branch[0]:
            other = br.q[:, b]
            c = sum(
                motion_cost(other[i - 1][None], other[i][None], robot.velocity)[0, 0]
                for i in range(1, 40)
            )
            assert mine <= c + 1e-9


# ------------------------------------------------------------------------------ collision


def test_motion_through_a_thin_plate_is_caught(robot):
    qm = np.array([0.0, -1.2, 1.2, 0.0, 0.8, 0.0])
    qa, qb = qm.copy(), qm.copy()
    qa[0], qb[0] = -0.3, 0.3  # A1 sweeps the flange through the plane y = 0
    flange = robot.fk(qm)[0, :3, 3]
    plate = make_plate(flange + [0.0, 0.0, 0.0], 1, size=120.0)
    chk = RobotCollision(robot, plate, arc_torch(), TORCH_TCP)
    assert chk.state_free(qa) and chk.state_free(qb)
    assert not chk.state_free(qm)
    hits = chk.path_hits(np.stack([qa, qb]))
    assert len(hits) == 1 and 0.2 < hits[0].t < 0.8
    away = make_plate(flange + [0.0, 2500.0, 0.0], 1, size=120.0)
    assert RobotCollision(robot, away, arc_torch(), TORCH_TCP).path_hits(np.stack([qa, qb])) == []


def test_free_verdicts_hold_under_dense_sampling(robot):
    """Whatever path_hits calls free, 400 FCL samples per motion find free too."""
    rng = np.random.default_rng(11)
    q0 = np.array([0.0, -1.2, 1.2, 0.0, 0.8, 0.0])
    flange = robot.fk(q0)[0, :3, 3]
    part = trimesh.util.concatenate(
        [
            make_plate(flange + [0.0, 300.0, -200.0], 1, size=250.0),
            make_plate(flange + [200.0, -250.0, 100.0], 0, size=250.0),
        ]
    )
    chk = RobotCollision(robot, part, arc_torch(), TORCH_TCP)
    n_free = n_blocked = 0
    for _ in range(12):
        qa = q0 + rng.normal(0, 0.15, 6)
        qb = q0 + rng.normal(0, 0.15, 6)
        if not (chk.state_free(qa) and chk.state_free(qb)):
            continue
        free = not chk.path_hits(np.stack([qa, qb]))
        dense = all(chk.state_free(qa + t * (qb - qa)) for t in np.linspace(0, 1, 400))
        if free:
            assert dense
            n_free += 1
        else:
            n_blocked += 1
    assert n_free >= 3  # the test exercised the free verdict


# ------------------------------------------------------------------------------ the route


def test_plan_robot_route_on_the_box_scene(robot):
    route = box_route()
    poses = down_poses(route)
    part = box_part()
    rr = plan_robot_route(
        route, poses, robot, tool=ToolOnRobot(TORCH_TCP, arc_torch()),
        cell=RobotCell(part, base=BOX_BASE),
    )  # fmt: skip
    assert rr.status == ("ok", "ok", "ok") and rr.stats["collision_free"] and rr.flips == ()
    # the torch's nozzle grazes the wall's end on the way round it (y = 62 mm, nozzle radius
    # 12.5 mm, wall end at y = 50): that leg is re-planned in joint space
    assert rr.stats["first_check_hits"] >= 1 and rr.replanned == (1,)
    wp = route.waypoints()
    T = rr.tcp(robot)
    ex = rr.exact
    assert ex[rr.weld_index].all() and not ex.all()
    np.testing.assert_allclose(T[ex, :3, 3], wp[rr.row[ex]], atol=1e-6)
    for k, i in enumerate(rr.weld_index):
        np.testing.assert_allclose(T[i, :3, 2], [0, 0, -1], atol=1e-9)
        xyz = route.joint_xyz[route.joint_ids.index(rr.weld_ids[k])]
        np.testing.assert_allclose(T[i, :3, 3], xyz, atol=1e-6)
    # an independent look: dense FCL samples of the final joint path (tool minus its contact
    # zone, as checked) touch nothing
    chk = RobotCollision(robot.with_base(BOX_BASE), part, arc_torch(), TORCH_TCP)
    for a, b in zip(rr.q[:-1], rr.q[1:], strict=True):
        assert all(chk.state_free(a + t * (b - a), zone=True) for t in np.linspace(0, 1, 60))
    back = RobotRoute.from_json(rr.to_json())
    np.testing.assert_array_equal(back.q, rr.q)
    assert back.status == rr.status and back.weld_branch.tolist() == rr.weld_branch.tolist()


def test_a_base_that_reaches_nothing_is_one_line_naming_the_field(robot):
    route = box_route()
    with pytest.raises(InputError) as ei:
        plan_robot_route(
            route,
            down_poses(route),
            robot,
            tool=ToolOnRobot(TORCH_TCP),
            cell=RobotCell(box_part(), base=base_pose(9000.0, 0.0, 0.0, 0.0)),
            settings=JointRouteSettings(check_collision=False),
        )
    assert ei.value.field == "--robot-base"
    assert "3 out of reach" in str(ei.value) and "\n" not in str(ei.value)


def test_search_along_a_line_finds_a_base_that_reaches_every_weld(robot):
    route = box_route()
    poses = down_poses(route)
    from weldplan.robot.route import tcp_waypoint_poses
    from weldplan.tool.poses import weld_rows

    T = tcp_waypoint_poses(route, poses)[weld_rows(route)] @ np.linalg.inv(TORCH_TCP)
    line = ((-3000.0, -1000.0, -700.0), (-500.0, -1000.0, -700.0))
    opts = BaseSearch(line=line, step=100.0, extra_yaws=())
    pl = search_base(robot, T, box_part(), opts, top=3)[0]
    assert pl.n_usable == 3 and pl.searched
    x, y, z, yaw = pl.xyz_yaw()
    assert y == pytest.approx(-1000.0) and z == pytest.approx(-700.0)
    # it faces the welds
    c = T[:, :3, 3].mean(axis=0)
    assert yaw == pytest.approx(math.degrees(math.atan2(c[1] - y, c[0] - x)), abs=1e-6)
    with pytest.raises(PlanningError):
        search_base(robot, T, box_part(), BaseSearch(line=((9000, 0, 0), (9500, 0, 0))))


@pytest.mark.slow
def test_demo_cell_with_the_shared_gun_and_a_searched_base(robot):
    """The demo cell end to end: route, gun poses, base search, configurations, collision."""
    import weldplan
    from weldplan.robot.route import tcp_waypoint_poses, tool_flange_tcp
    from weldplan.tool import plan_weld_poses, shared_spot_gun
    from weldplan.tool.model import SHARED_GUN_DIR

    require_shared("tools", "spot_welding_gun")
    cell = weldplan.demo_cell()
    route = weldplan.plan_route(cell, rng=0)
    gun = shared_spot_gun()
    poses = plan_weld_poses(cell, route, gun)
    F = tool_flange_tcp(robot, SHARED_GUN_DIR / "spot_welding_gun.urdf", "nozzle_tip")
    rr = plan_robot_route(
        route,
        poses,
        robot,
        tool=ToolOnRobot(F, gun),
        cell=RobotCell(cell.part, search=BaseSearch()),
        settings=JointRouteSettings(replan=False),
    )
    allowed = {"ok", "out_of_reach", "joint_limit", "singular", "no_pose", "collision"}
    assert set(rr.status) <= allowed and len(rr.status) == 15
    # welds without a gun pose are no_pose, and only they
    assert [s == "no_pose" for s in rr.status] == [not p.ok for p in poses.poses]
    assert rr.n_ok >= 8
    # every exact row is the route's TCP pose, by FK of the URDF chain
    T = rr.tcp(robot)
    want = tcp_waypoint_poses(route, poses)[rr.row]
    ex = rr.exact
    np.testing.assert_allclose(T[ex], want[ex], atol=1e-6)
    ok = np.array([s == "ok" for s in rr.status])
    assert (rr.weld_branch[ok] >= 0).all() and rr.flips == ()
    # a weld charged with a collision has a blocked motion at or next to it
    assert rr.stats["collision_free"] == (not rr.stats["hits"])
