"""The base search scores each weld with its alternative tool poses
(weldplan.robot.placement.altreach, issue 17): a base that serves more welds, with any of their free
poses, wins over one that serves more of the poses the tool stage happened to choose first."""

from __future__ import annotations

import dataclasses

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from tests.robot_fixtures import shared_robot
from tests.robot_helpers import TORCH_TCP
from weldplan.bench.robot import straight_route
from weldplan.io.joints import Joints
from weldplan.robot.placement import (
    BaseSearch,
    ReachTest,
    alternative_flange_poses,
    place_for_poses,
    spread,
)
from weldplan.robot.settings import ToolOnRobot
from weldplan.tool import PoseSearchSettings, arc_torch, plan_weld_poses
from weldplan.tool.poses import rotation_angles

#: four welds on a long plate, welded from above; the robot's bases on a line beside them
WELDS_Y = (0.0, 700.0, -700.0, 2000.0)
LINE = ((-2000.0, -1500.0, -500.0), (-2000.0, 1500.0, -500.0))
#: A6 narrowed to a 20 deg window (a dress pack), A1 and A4 to +-90: a torch from above is
#: reached in one or two of its 24 spins, which ones depending on where the base stands
NARROW_DEG = {0: (-90.0, 90.0), 3: (-90.0, 90.0), 5: (140.0, 160.0)}


def _narrow(robot):
    lo, hi = np.degrees(robot.lower), np.degrees(robot.upper)
    for j, (a, b) in NARROW_DEG.items():
        lo[j], hi[j] = a, b
    return dataclasses.replace(robot, lower=np.radians(lo), upper=np.radians(hi))


def _station():
    plate = trimesh.creation.box((200, 3200, 2)).apply_translation((0, 650, -1))
    joints = Joints(
        ids=["a", "b", "c", "d"],
        xyz=[[0.0, y, 0.0] for y in WELDS_Y],
        directions=[[0.0, 0.0, 1.0]] * 4,
    )
    route = straight_route(joints)
    search = PoseSearchSettings(cone=0.0, spin_step=15.0)
    poses = plan_weld_poses(plate, route, arc_torch(bend_angle=0.0), search)
    return plate, route, poses


def _reached(robot, base, poses) -> list[bool]:
    """Per weld: one of its free poses is reached from ``base`` (the reach test over all)."""
    test = ReachTest(robot.with_base(base), TORCH_TCP)
    out = []
    for p, alts in zip(poses.poses, poses.alternatives, strict=True):
        T = np.tile(np.eye(4), (len(alts), 1, 1))
        T[:, :3, :3] = Rotation.from_quat(np.roll(alts, -1, axis=1)).as_matrix()
        T[:, :3, 3] = p.position
        out.append(any(v is None for v in test.verdicts(T)))
    return out


def test_the_tool_stage_hands_on_every_free_pose_of_a_weld_the_chosen_one_first():
    _, _, poses = _station()
    assert len(poses.alternatives) == 4
    for p, alts in zip(poses.poses, poses.alternatives, strict=True):
        assert alts.shape == (24, 4)  # a flat plate: every spin is free
        assert np.allclose(alts[0], p.quaternion)
        ang = rotation_angles(alts, alts[:1])[:, 0]
        assert np.all(np.diff(ang) >= -1e-9)  # by rotation from the chosen one
    # not written to JSON: a route read back has none, and the search scores its poses only
    assert type(poses).from_json(poses.to_json()).alternatives == ()


def test_spread_takes_the_first_then_the_farthest():
    spins = np.arange(0, 360, 15)[:, None]
    q = np.roll(Rotation.from_euler("z", spins, degrees=True).as_quat(), 1, axis=1)
    assert spread(q, 30).tolist() == list(range(24))
    assert spread(q, 2).tolist() == [0, 12]  # 180 deg away
    assert sorted(spread(q, 4).tolist()) == [0, 6, 12, 18]


def test_the_searched_base_serves_every_weld_with_one_of_its_free_poses():
    robot = _narrow(shared_robot())
    plate, route, poses = _station()
    search = BaseSearch(line=LINE, step=500.0, extra_yaws=())
    # scored with every weld's free poses, a base that serves all four wins
    tool = ToolOnRobot(TORCH_TCP)
    pl = place_for_poses(robot, route, poses, tool, plate, None, search, alternatives=True)
    assert _reached(robot, pl.base, poses) == [True] * 4
    assert pl.n_usable == 4 and pl.searched and pl.min_manipulability > 0
    # scored with the chosen poses only (the tool stage took spin 0 at every weld, first among
    # equals): from the end of the line at y = -1500 two of those are reached, more than from
    # anywhere else, but weld d (2 m along the plate) is out of reach there whatever the pose
    only = place_for_poses(robot, route, poses, tool, plate, None, search)  # the default
    assert only.xyz_yaw()[1] == -1500.0
    assert _reached(robot, only.base, poses) == [True, True, True, False]


def test_the_alternatives_become_flange_poses_spread_the_chosen_one_first():
    _, route, poses = _station()
    assert alternative_flange_poses(
        dataclasses.replace(poses, alternatives=()), route.order, TORCH_TCP
    ) is None  # fmt: skip
    alts = alternative_flange_poses(poses, route.order, TORCH_TCP, k=5)
    assert [len(a) for a in alts] == [5] * 4
    for p, a in zip(poses.poses, alts, strict=True):
        T = a @ TORCH_TCP  # back to the TCP: on the weld, the chosen orientation first
        assert np.allclose(T[:, :3, 3], p.position)
        w, x, y, z = p.quaternion
        assert np.allclose(T[0, :3, :3], Rotation.from_quat([x, y, z, w]).as_matrix())
        assert np.allclose(T[:, :3, 2], [0.0, 0.0, -1.0])  # every spin points down


def test_a_weld_counts_free_when_one_of_its_poses_has_a_branch_clear_of_the_part():
    from weldplan.robot.collision import RobotCollision
    from weldplan.robot.placement import alt_free, base_pose

    robot = shared_robot().with_base(base_pose(-1500.0, 0.0, -500.0, 0.0))
    plate = trimesh.creation.box((600, 600, 2)).apply_translation((0, 0, -1))
    block = trimesh.creation.box((150, 150, 150)).apply_translation((-570, 0, 1070))
    spins = Rotation.from_euler("z", np.arange(0, 360, 30)[:, None], degrees=True).as_matrix()
    T = np.tile(np.eye(4), (12, 1, 1))
    T[:, :3, :3] = np.diag([1.0, -1.0, -1.0]) @ spins  # from above, 12 spins
    far = T.copy()
    far[:, :3, 3] = (4000.0, 0.0, 0.0)  # out of reach
    alts = [T @ np.linalg.inv(TORCH_TCP), far @ np.linalg.inv(TORCH_TCP)]
    need = np.array([True, True])
    for part, first in ((plate, True), (trimesh.util.concatenate([plate, block]), False)):
        checker = RobotCollision(robot, part, None, TORCH_TCP)
        got = alt_free(robot, checker, alts, need, 5.0)
        # the same answer as the reach test over every pose (one FCL query per pose there)
        test = ReachTest(robot, TORCH_TCP, checker)
        assert got.tolist() == [any(v is None for v in test.verdicts(T)), False]
        assert got.tolist() == [first, False]  # the block is over the forearm's way
    assert alt_free(robot, None, alts, need, 5.0).tolist() == [True, False]  # reach only
    assert not alt_free(robot, None, alts, ~need, 5.0).any()  # none needed
