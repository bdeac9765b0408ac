"""The robot's reach test in the pose choice (weldplan.robot.placement.posechoice, issue 17): the
robot vetoes gun poses it cannot take (joint limits, out of reach, a link in the part) and the pose
choice takes the least-rotation pose among those it can."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from tests.robot_fixtures import shared_robot
from tests.robot_helpers import TORCH_TCP, down_poses
from tests.route_fixtures import box_part, box_route
from weldplan.io.joints import Joints
from weldplan.robot.collision import RobotCollision
from weldplan.robot.placement import BaseSearch, ReachTest, base_pose, place_for_poses
from weldplan.robot.settings import ToolOnRobot
from weldplan.tool import PoseSearchSettings, arc_torch, plan_weld_poses, verify_poses
from weldplan.tool.poses import all_of, candidate_rotations, local_candidates

#: the robot 1.5 m behind the welds, 0.5 m below the plate: the torch reaches them from above
BASE = base_pose(-1500.0, 0.0, -500.0, 0.0)
#: A1 kept in front (a fence behind the robot), A4 and A6 narrowed (a dress pack that must not
#: wind): from above, only a torch spun 90 deg about its axis is inside them (A6 = 90 deg on the
#: only branch with A1 and A4 in +-90; spin 270 would need A1 = 180, over the shoulder)
NARROW_DEG = {0: (-90.0, 90.0), 3: (-90.0, 90.0), 5: (80.0, 100.0)}
DOWN = np.diag([1.0, -1.0, -1.0])  # TCP z straight down, spin 0


def _plate() -> trimesh.Trimesh:
    return trimesh.creation.box((600, 600, 2)).apply_translation((0, 0, -1))


def _welds() -> Joints:
    return Joints(ids=["a", "b"], xyz=[[0, 0, 0], [100, 50, 0]], directions=[[0, 0, 1.0]] * 2)


def _narrow(robot):
    lo, hi = np.degrees(robot.lower), np.degrees(robot.upper)
    for j, (a, b) in NARROW_DEG.items():
        lo[j], hi[j] = a, b
    return dataclasses.replace(robot, lower=np.radians(lo), upper=np.radians(hi))


def _tcp(p, R=DOWN) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def test_the_least_rotation_pose_out_of_the_limits_gives_way_to_the_reachable_one():
    robot = _narrow(shared_robot().with_base(BASE))
    plate, torch = _plate(), arc_torch(bend_angle=0.0)
    opts = PoseSearchSettings(cone=0.0, spin_step=15.0)
    plain = plan_weld_poses(plate, _welds(), torch, opts)
    assert [p.spin for p in plain.poses] == [0.0, 0.0]  # spin 0 first among equals
    test = ReachTest(robot, TORCH_TCP)
    # the exact answer, independently: of the 24 spins of a weld from above, only 90 deg
    # passes (IK of each spin; the limits decide)
    local, params = local_candidates(0.0, 7.5, 15.0, 8)
    R = candidate_rotations(np.array([[0.0, 0.0, -1.0]]), local)[0]
    verdicts = test.verdicts(np.stack([_tcp((0, 0, 0), r) for r in R]))
    assert [s for s, v in zip(params[:, 0], verdicts, strict=True) if v is None] == [90.0]
    assert verdicts[0].startswith("joint_limit A6 ")

    # composed with a test that passes everything (all_of keeps the batch judgment)
    accept = all_of(lambda i, T: None, ReachTest(robot, TORCH_TCP))
    poses = plan_weld_poses(plate, _welds(), torch, opts, accept=accept)
    assert [p.spin for p in poses.poses] == [90.0, 90.0]
    assert [p.tilt for p in poses.poses] == [0.0, 0.0] and not any(p.note for p in poses.poses)
    assert poses.total_rotation == pytest.approx(0.0, abs=1e-9)
    # one pick vetoed per weld, then its 23 other spins judged at once: 22 vetoed
    assert poses.stats["accept_exhausted"] == 0 and poses.stats["vetoed"] == 2
    assert poses.stats["batch_judged"] == 46 and poses.stats["batch_vetoed"] == 44
    assert verify_poses(poses, plate, torch).ok
    # the chosen poses are reached: FK of a usable IK solution is the flange pose
    for p in poses.poses:
        T = poses_tcp(p) @ np.linalg.inv(TORCH_TCP)
        sol = robot.ik(T)
        assert len(sol) and robot.in_limits(sol.q).any()
        assert np.allclose(robot.fk(sol.q[robot.in_limits(sol.q)])[0], T, atol=1e-6)


def poses_tcp(p) -> np.ndarray:
    w, x, y, z = p.quaternion
    return _tcp(p.position, Rotation.from_quat([x, y, z, w]).as_matrix())


def test_the_reasons_name_the_cause():
    robot = shared_robot().with_base(BASE)
    box = trimesh.creation.box((150, 150, 150)).apply_translation((-570, 0, 1070))
    part = trimesh.util.concatenate([_plate(), box])  # a block over the forearm's way
    free = ReachTest(robot, TORCH_TCP, RobotCollision(robot, _plate(), None, TORCH_TCP))
    blocked = ReachTest(robot, TORCH_TCP, RobotCollision(robot, part, None, TORCH_TCP))
    narrow = ReachTest(_narrow(robot), TORCH_TCP)
    here, far = _tcp((0, 0, 0)), _tcp((3000, 0, 0))
    assert free.verdicts(np.stack([here, far])) == [None, "out_of_reach"]
    assert blocked(0, here) == "link_3 in the part"
    spun = _tcp((0, 0, 0), DOWN @ Rotation.from_euler("z", 30, degrees=True).as_matrix())
    assert narrow(0, spun) == "joint_limit A6 150 deg (limits 80..100)"
    assert (free.calls, blocked.calls, narrow.calls) == (2, 1, 1)
    assert free.vetoes == {"out_of_reach": 1} and blocked.vetoes == {"link_3": 1}


def test_a_weld_whose_every_pose_puts_the_arm_in_the_part_keeps_its_pose_with_a_note():
    robot = shared_robot().with_base(BASE)
    box = trimesh.creation.box((150, 150, 150)).apply_translation((-570, 0, 1070))
    part = trimesh.util.concatenate([_plate(), box])
    torch = arc_torch(bend_angle=0.0)
    test = ReachTest(robot, TORCH_TCP, RobotCollision(robot, part, None, TORCH_TCP))
    opts = PoseSearchSettings(cone=0.0, spin_step=30.0)
    plain = plan_weld_poses(part, _welds(), torch, opts)
    poses = plan_weld_poses(part, _welds(), torch, opts, accept=test)
    # a spin does not move the forearm: every pose is vetoed (the pick, then the other 11 at
    # once), the least-rotation one is kept
    assert [p.quaternion for p in poses.poses] == [p.quaternion for p in plain.poses]
    assert all(p.note.startswith("12 free poses vetoed (link_3 in the part)") for p in poses.poses)
    assert test.vetoes == {"link_3": 24} and poses.stats["vetoed"] == 2


def test_the_base_is_searched_for_the_first_pass_poses_and_serves_them():
    robot = shared_robot()
    route = box_route(directions=True)
    poses = down_poses(route)
    part = box_part()
    checker = RobotCollision(robot, part, None, TORCH_TCP)
    pl = place_for_poses(
        robot, route, poses, ToolOnRobot(TORCH_TCP), part, checker,
        BaseSearch(step=500.0, extra_yaws=()),
    )  # fmt: skip
    assert pl.searched and pl.candidates > 0
    rb = robot.with_base(pl.base)
    test = ReachTest(rb, TORCH_TCP, checker.with_robot(rb))
    T = np.stack([poses_tcp(p) for p in poses.poses])
    assert test.verdicts(T) == [None] * len(T)


def test_a_tool_that_straddles_is_turned_over_when_the_test_vetoes_its_approach_side():
    plate, torch = _plate(), arc_torch(bend_angle=0.0)

    def from_below(i: int, T: np.ndarray) -> str | None:  # the robot stands under the plate
        return "joint_limit A5" if T[2, 2] < 0 else None

    opts = PoseSearchSettings(cone=0.0, spin_step=30.0, both_sides=True)
    plain = plan_weld_poses(plate, _welds(), torch, opts)
    assert not any(p.flipped for p in plain.poses)  # the approach side first
    capped = PoseSearchSettings(cone=0.0, spin_step=30.0, both_sides=True, max_vetoes=12)
    poses = plan_weld_poses(plate, _welds(), torch, capped, accept=from_below)
    # 12 spins from above, all vetoed: the test is lifted, then put back on the turned-over
    # candidates, and the first of those (spin 0, from below) passes at both welds
    assert [(p.flipped, p.spin, p.note) for p in poses.poses] == [(True, 0.0, "")] * 2
    assert poses.stats["vetoed"] == 24 and poses.stats["accept_exhausted"] == 0
    assert poses.total_rotation == pytest.approx(0.0, abs=1e-9)
    assert verify_poses(poses, plate, torch).ok
    # without both sides, the weld keeps its approach-side pose with the note
    one_side = PoseSearchSettings(cone=0.0, spin_step=30.0)
    kept = plan_weld_poses(plate, _welds(), torch, one_side, accept=from_below)
    assert all(not p.flipped and p.note.startswith("12 free poses vetoed") for p in kept.poses)


def test_plan_with_a_robot_base_judges_the_poses_from_it(tmp_path, capsys):
    import json

    from tests.cli_helpers import run_cli
    from tests.robot.test_robot_cli import _robot_urdf, _torch_urdf
    from tests.route_fixtures import write_box_station

    _, mesh, joints = write_box_station(tmp_path)
    argv = [
        "plan", str(mesh), str(joints), "--margin", "50", "-o", str(tmp_path / "r.csv"),
        "--json", str(tmp_path / "r.json"), "--tool", str(_torch_urdf(tmp_path)),
        "--robot", str(_robot_urdf()), "--robot-base=-1800,0,-700,0",
    ]  # fmt: skip
    assert run_cli(argv) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("robot reach test"))
    # the four welds' least-rotation poses are reached from that base: judged once, none vetoed
    assert "4 gun pose(s) judged, 0 vetoed; base given" in row
    poses = json.loads((tmp_path / "r.json").read_text())["tool"]["poses"]
    assert poses["stats"]["accept_calls"] == 4 and not any(p["note"] for p in poses["poses"])
