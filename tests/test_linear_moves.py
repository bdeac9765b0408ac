"""Checked linear moves (weldplan.robot.route.linear) and where the program emits LIN / MoveL."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
from weldplan.robot.route import check_linear_moves, line_poses
from weldplan.weld.route import Leg, Route


def _long_route():
    """Two welds 600 mm apart on a plate, the straight leg 10 mm above it."""
    A, B = np.array([-300.0, 0, 0]), np.array([300.0, 0, 0])
    vA, vB = A + [0, 0, 10], B + [0, 0, 10]
    return Route(
        order=("A", "B"),
        legs=(Leg("A", "B", [A, vA, vB, B], "straight"),),
        joint_ids=("A", "B"),
        joint_xyz=np.array([A, B]),
        directions=np.tile([0, 0, 1.0], (2, 1)),
        virtual_xyz=np.array([vA, vB]),
        settings={"clearance": 5.0},
    )


def _plate():
    plate = trimesh.creation.box(extents=[800, 200, 2])
    plate.apply_translation([0, 0, -1])
    return plate


@pytest.fixture(scope="module")
def long_joint_route():
    robot = shared_robot()
    Tft, _ = gun_tcp(robot)
    route, Q = box_joint_route(robot, Tft, _long_route())
    return robot, Tft, route, Q


def test_line_poses_are_straight_and_end_on_both_targets():
    Ta, Tb = np.eye(4), np.eye(4)
    Tb[:3, 3] = [100.0, 0.0, 0.0]
    Tb[:3, :3] = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])  # 90 deg about z
    P = line_poses(Ta, Tb, 5.0, 2.0)
    assert len(P) == 46  # 90 deg at 2 deg a step beats 100 mm at 5 mm
    np.testing.assert_allclose(P[0], Ta, atol=1e-12)
    np.testing.assert_allclose(P[-1], Tb, atol=1e-12)
    np.testing.assert_allclose(P[:, 1:, 3][:, :2], 0.0, atol=1e-12)
    assert np.all(np.diff(P[:, 0, 3]) > 0)


def test_a_lin_through_an_obstacle_is_emitted_as_a_joint_move(long_joint_route):
    from weldplan.robot.program import robot_program
    from weldplan.robot.settings import ProgramSettings, ToolOnRobot

    robot, Tft, route, Q = long_joint_route
    # the Cartesian check alone (the 600 mm move's joint path strays from the line by more than
    # the default 1 mm, which keeps it a joint move for the timing's sake)
    tool = ToolOnRobot(Tft, mass=2.0, cog=np.zeros(3))
    common = dict(settings=ProgramSettings(weld_time=0.5, line_tolerance=None))
    free = robot_program(route, Q, robot, tool, part=_plate(), **common)
    moves = [(t.kind, t.row, t.move) for t in free.program.targets]
    assert ("via", 2, "linear") in moves  # the 600 mm straight move is verified linear
    # a 20 mm block where the flange passes half way along that move, 40 mm above it
    F = robot.fk(Q[[1, 2]])[:, :3, 3].mean(axis=0)
    block = trimesh.creation.box(extents=[20, 20, 20])
    block.apply_translation(F + [0.0, 0.0, 40.0])
    part = trimesh.util.concatenate([_plate(), block])
    hit = robot_program(route, Q, robot, tool, part=part, **common)
    moves_hit = [(t.kind, t.row, t.move) for t in hit.program.targets]
    assert ("via", 2, "joint") in moves_hit
    assert ("weld", 3, "linear") in moves_hit  # the short moves far from the block stay linear
    from weldplan.io.posts.krl import render_krl
    from weldplan.io.posts.parse import parse_krl

    src, dat = render_krl(hit.program)
    kinds = [m[0] for m in parse_krl(src, dat).moves]
    assert kinds.count("PTP") == sum(t.move == "joint" for t in hit.program.targets)


def test_check_refuses_unchecked_flipping_and_mis_turned_moves(long_joint_route):
    robot, Tft, route, Q = long_joint_route
    qa, qb = Q[1], Q[2]
    # no checker: kinematically fine, but nothing is linear without the collision check
    c = check_linear_moves(robot, Tft, qa, qb, checker=None)
    assert c.reason == ("collision",) and not c.ok[0] and c.samples[0] >= 121  # 600 mm at 5 mm
    # the same pose with A6 a full turn away: the controller would arrive elsewhere
    qt = qb.copy()
    qt[5] += 2 * np.pi if qt[5] < 0 else -2 * np.pi
    assert check_linear_moves(robot, Tft, qa, qt).reason == ("turn",)
    # the target on another IK branch: the line from qa's branch ends in another configuration
    sol = robot.ik(robot.fk(qb)[0])
    other = sol.q[np.argmax(np.abs(sol.q - qb).max(axis=1))]
    assert check_linear_moves(robot, Tft, qa, other).reason[0] in ("turn", "flip", "no_ik")


def test_by_default_a_linear_move_also_keeps_its_joint_path_near_the_line(long_joint_route):
    from weldplan.robot.program import joint_line_deviation, robot_program
    from weldplan.robot.settings import ToolOnRobot

    robot, Tft, route, Q = long_joint_route
    b = robot_program(route, Q, robot, ToolOnRobot(Tft, mass=2.0, cog=np.zeros(3)), part=_plate())
    assert float(joint_line_deviation(robot, Tft, Q[1], Q[2])[0]) > 1.0
    assert ("via", 2, "joint") in [(t.kind, t.row, t.move) for t in b.program.targets]
