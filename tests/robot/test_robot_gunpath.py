"""The robot follows the gun's transitions (weldplan.robot.route.gunpath): the route along them, its
IK steps, the contact zone only at the spots, and a scene only the gun's path serves."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.conftest import require_shared
from tests.robot_helpers import BOX_BASE, TORCH_TCP, down_poses
from tests.route_fixtures import IDS, SPOTS, box_part
from weldplan.errors import InputError
from weldplan.robot.route import GunRoute, gun_exits, gun_route, legs_taken
from weldplan.tool.poses import weld_rows
from weldplan.tool.transitions import BLOCKED, DIRECT, ToolPath, Transition
from weldplan.weld.route import Leg, Route

Q_DOWN = (0.0, 1.0, 0.0, 0.0)  # TCP z -> -z
LIFT = 100.0  # mm: over the box part's 60 mm wall


def two_weld_route() -> Route:
    """A -> B of the box scene, straight through its wall (the point tip's data only)."""
    A, B = SPOTS[0], SPOTS[1]
    return Route(order=("A", "B"), legs=(Leg("A", "B", [A, B]),), joint_ids=IDS, joint_xyz=SPOTS)


def over_the_wall(status: str = DIRECT) -> ToolPath:
    """The tool's transition A -> B: lift 100 mm, move over the wall, lower; a turn of 40 deg
    about z on the way (so the steps are cut by angle too)."""
    A, B = SPOTS[0], SPOTS[1]
    P = np.array([A, A + [0, 0, LIFT], B + [0, 0, LIFT], B])
    turned = Rotation.from_euler("z", 40, degrees=True) * Rotation.from_quat([1.0, 0, 0, 0])
    qt = np.roll(turned.as_quat(), 1)
    Q = np.array([Q_DOWN, Q_DOWN, qt, qt])
    t = Transition("A", "B", P, Q, ("retract", "move", "approach"), status)
    return ToolPath(order=("A", "B"), transitions=(t,))


def poses_for(route: Route, path: ToolPath):
    """Down poses, B's turned as the transition ends."""
    poses = down_poses(route)
    b = dataclasses.replace(poses.poses[1], quaternion=tuple(path.transitions[0].quaternions[-1]))
    return dataclasses.replace(poses, poses=(poses.poses[0], b))


def test_the_gun_route_steps_along_the_transition_and_exempts_the_zone_at_the_spots_only():
    route, path = two_weld_route(), over_the_wall()
    gr = gun_route(route, poses_for(route, path), path, contact_radius=20.0, step_mm=25.0)
    assert isinstance(gr, GunRoute) and gr.route.order == ("A", "B") and gr.via == ("axial",)
    P = gr.route.waypoints()
    np.testing.assert_array_equal(P[0], SPOTS[0])
    np.testing.assert_array_equal(P[-1], SPOTS[1])
    np.testing.assert_allclose(gr.tcp[:, :3, 3], P)
    # steps of at most 25 mm and 10 deg, every corner of the transition kept
    assert np.linalg.norm(np.diff(P, axis=0), axis=1).max() <= 25.0 + 1e-9
    R = Rotation.from_matrix(gr.tcp[:, :3, :3])
    assert np.degrees((R[:-1].inv() * R[1:]).magnitude()).max() <= 10.0 + 1e-9
    for corner in path.transitions[0].positions:  # and a step 20 mm off each spot
        assert np.min(np.linalg.norm(P - corner, axis=1)) < 1e-9
    # the weld rows carry the poses' own orientations
    q = gr.quaternions()
    np.testing.assert_allclose(q[0], Q_DOWN, atol=1e-12)
    np.testing.assert_allclose(np.abs(q[-1]), np.abs(path.transitions[0].quaternions[-1]))
    # the zone: only motions with both ends within 20 mm of one spot
    near = [
        min(np.linalg.norm(P[i] - SPOTS[0]), np.linalg.norm(P[i] - SPOTS[1])) <= 20.0
        for i in range(len(P))
    ]
    assert gr.zone.any() and not gr.zone.all()
    for i, z in enumerate(gr.zone):
        assert not z or (near[i] and near[i + 1])


def test_a_blocked_transition_is_one_motion_spot_to_spot():
    route, path = two_weld_route(), over_the_wall(BLOCKED)
    gr = gun_route(route, poses_for(route, path), path, contact_radius=20.0)
    assert gr.via == ("blocked",) and len(gr.route.waypoints()) == 2
    assert not gr.zone.any()  # 80 mm apart: the spot-to-spot motion keeps no exemption
    assert legs_taken(gr.via, ("ok", "ok"), ()) == ["joint"]
    assert legs_taken(("slide", "slide"), ("ok", "collision", "ok"), ()) == ["gun slide"]
    assert legs_taken(("slide",), ("ok", "ok"), (0,)) == ["detour"]


@pytest.mark.slow
def test_the_robot_serves_both_welds_only_along_the_gun_path():
    """Over the box part's wall: the robot's own leg A -> B (point tip, orientation slerped)
    drives the torch through the wall; along the gun's lift-move-lower it is collision-free with
    no detour, FK puts the TCP on the gun's path at every exact row, and the route JSON's
    re-check (verify_robot_route, its own FK and collision check) passes."""
    from weldplan.robot import load_robot
    from weldplan.robot.program import attach_robot_route, verify_robot_route
    from weldplan.robot.route import plan_robot_route
    from weldplan.robot.settings import JointRouteSettings, RobotCell, ToolOnRobot
    from weldplan.tool import arc_torch

    robot = load_robot(require_shared("robots", "kuka_kr150r3100_2") / "kr150r3100_2.urdf")
    route, path = two_weld_route(), over_the_wall()
    poses = poses_for(route, path)
    part, torch = box_part(), arc_torch()
    kw = dict(
        tool=ToolOnRobot(TORCH_TCP, torch), cell=RobotCell(part, base=BOX_BASE),
        settings=JointRouteSettings(replan=False), rng=0,
    )  # fmt: skip
    own = plan_robot_route(route, poses, robot, **kw)
    assert own.stats["collision_free"] is False and own.n_ok < 2
    gr = gun_route(route, poses, path, contact_radius=20.0)
    rr = plan_robot_route(gr.route, gr.poses, robot, tcp_poses=gr.tcp, zone=gr.zone, **kw)
    assert rr.stats["collision_free"] is True and rr.n_ok == 2 and rr.replanned == ()
    assert rr.exact.all() and not rr.flips
    T = robot.with_base(rr.base).fk(rr.q) @ TORCH_TCP
    np.testing.assert_allclose(T[:, :3, 3], gr.tcp[rr.row, :3, 3], atol=1e-6)
    np.testing.assert_allclose(T[:, :3, :3], gr.tcp[rr.row, :3, :3], atol=1e-8)
    # the route JSON: the point-tip route, its poses, the robot route and the route it followed
    carried = dataclasses.replace(route, tool={"poses": poses.to_dict()})
    carried = attach_robot_route(carried, rr, urdf=robot_urdf(), contact_radius=20.0, gun=gr)
    check = verify_robot_route(carried, rr, robot, part, torch)
    assert check.ok, check.describe()
    # a followed route that does not weld B at B's pose is refused, whatever its FK says
    bad = json.loads(json.dumps(carried.tool))
    bad["robot"]["follows"]["quaternions"][-1] = list(Q_DOWN)
    with pytest.raises(InputError, match="does not weld the route's welds at their poses"):
        verify_robot_route(dataclasses.replace(carried, tool=bad), rr, robot, part, torch)


def robot_urdf():
    return require_shared("robots", "kuka_kr150r3100_2") / "kr150r3100_2.urdf"


def test_the_gun_exits_are_the_motions_before_the_move_longest_first():
    route, path = two_weld_route(), over_the_wall()
    gr = gun_route(route, poses_for(route, path), path, contact_radius=20.0)
    (a,) = gun_exits(path, "A", 20.0)
    (b,) = gun_exits(path, "B", 20.0)
    # A's: the 100 mm lift off A; B's: the lowering onto B, reversed (from B up)
    np.testing.assert_allclose(a[0, :3, 3], SPOTS[0])
    np.testing.assert_allclose(a[-1, :3, 3], SPOTS[0] + [0, 0, LIFT])
    np.testing.assert_allclose(b[0, :3, 3], SPOTS[1])
    np.testing.assert_allclose(b[-1, :3, 3], SPOTS[1] + [0, 0, LIFT])
    assert np.linalg.norm(a[1, :3, 3] - a[0, :3, 3]) == pytest.approx(20.0)  # zone, then whole
    rows = weld_rows(gr.route)
    assert set(gr.exits) == {int(rows[0]), int(rows[1])}
    # a short lift is left to the robot's own retracts; a blocked transition proves nothing
    short = over_the_wall()
    t = short.transitions[0]
    P = np.array(t.positions)
    P[1:3, 2] = 15.0
    lifted = dataclasses.replace(short, transitions=(dataclasses.replace(t, positions=P),))
    assert gun_exits(lifted, "A", 20.0) == ()
    assert gun_exits(over_the_wall(BLOCKED), "A", 20.0) == ()


@pytest.mark.slow
def test_a_detour_leaves_a_weld_along_the_gun_exit_first():
    """Detour.leave follows the gun's proven exit (IK step by step, same branch), every motion
    free for the robot and torch; FK puts the TCP on the exit's poses."""
    from weldplan.robot import load_robot
    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.route import Detour
    from weldplan.tool import arc_torch

    robot = load_robot(robot_urdf()).with_base(BOX_BASE)
    route, path = two_weld_route(), over_the_wall()
    gr = gun_route(route, poses_for(route, path), path, contact_radius=20.0)
    chk = RobotCollision(robot, box_part(), arc_torch(), TORCH_TCP)
    det = Detour(robot, chk, gr.tcp, TORCH_TCP, 5.0, "rrtconnect", 1.0, 0, exits=gr.exits)
    sol = robot.ik(gr.tcp[0] @ np.linalg.inv(TORCH_TCP))
    q0, br = sol.q[0], int(sol.branch[0])
    P = det.leave(q0, 0, br)
    assert P is not None and det.left_by == {"gun exit": 1}
    T = robot.fk(P) @ TORCH_TCP
    np.testing.assert_allclose(T[:, :3, 3], gr.exits[0][0][1:, :3, 3], atol=1e-6)
    Q = np.vstack([q0, P])
    zone = np.zeros(len(P), dtype=bool)
    zone[0] = True  # the first step, within the contact radius of the spot
    assert chk.path_hits(Q, zone) == []


@pytest.mark.slow
def test_a_tail_retract_leaves_the_weld_with_the_contact_zone_exempt():
    """The route after the last served weld is blocked (through the wall) and its motion off the
    weld was to be checked with the whole tool (a gun leg away from the spots): the retract that
    replaces it is checked from the weld with the zone exempt, as retract() proved it, and the
    assembled tail passes the final check (regression: it kept the whole-tool flag, and the
    final check refused the run)."""
    from weldplan.robot import load_robot
    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.route import Detour
    from weldplan.robot.route.walkpath import JointPath
    from weldplan.robot.route.walkpath import tail as _tail
    from weldplan.tool import arc_torch

    robot = load_robot(robot_urdf()).with_base(BOX_BASE)
    route, path = two_weld_route(), over_the_wall(BLOCKED)
    gr = gun_route(route, poses_for(route, path), path, contact_radius=20.0)
    chk = RobotCollision(robot, box_part(), arc_torch(), TORCH_TCP)
    det = Detour(robot, chk, gr.tcp, TORCH_TCP, 5.0, "rrtconnect", 1.0, 0)
    sols = [robot.ik(T @ np.linalg.inv(TORCH_TCP)) for T in gr.tcp]
    Q = np.array([s.q[0] for s in sols])
    br = np.array([int(s.branch[0]) for s in sols])
    own = np.append(gr.zone, True)
    assert not own[0] and not chk.motion_free(Q[0], Q[1], zone=False)
    out = JointPath()
    out.add(Q[0], 0, True, int(br[0]), zone=bool(own[0]))
    _tail(det, out, Q, np.array([True, True]), br, 0, own, blocked={0})
    Qo, row, exact, _, zone = out.arrays()
    assert zone[0] and list(row) == [0, 1] and not exact[1]
    assert chk.path_hits(Qo, zone) == []
