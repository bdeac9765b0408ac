"""The robot's joint-space roadmaps: a base chosen by the welds it can join, legs through them."""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import pytest
import trimesh

pytest.importorskip("ompl")

from tests.conftest import require_shared  # noqa: E402
from tests.robot_helpers import TORCH_TCP, make_plate  # noqa: E402
from weldplan.motion.roadmap import RoadmapSettings  # noqa: E402
from weldplan.robot import load_robot  # noqa: E402
from weldplan.robot.collision import RobotCollision  # noqa: E402
from weldplan.robot.placement import (  # noqa: E402  # noqa: E402
    LegRoadmap,
    Placement,
    base_pose,
    branch_roadmap,
    join_welds,
    rank_bases,
)
from weldplan.robot.route import Detour  # noqa: E402
from weldplan.robot.route.configs import joint_path  # noqa: E402
from weldplan.robot.settings import PlacementSettings  # noqa: E402
from weldplan.tool import arc_torch  # noqa: E402

SMALL = RoadmapSettings(milestones=10, neighbours=6, query_neighbours=6)


@pytest.fixture(scope="module")
def robot():
    d = require_shared("robots", "kuka_kr150r3100_2")
    return load_robot(d / "kr150r3100_2.urdf")


def plate_scene(robot):
    """A1 sweeps the torch through a plate (test_robot_replan's scene): ``(checker, qa, qb)``."""
    qm = np.array([0.0, -1.2, 1.2, 0.0, 0.8, 0.0])
    qa, qb = qm.copy(), qm.copy()
    qa[0], qb[0] = -0.3, 0.3
    plate = make_plate(robot.fk(qm)[0, :3, 3], 1, size=160.0)
    return RobotCollision(robot, plate, arc_torch(), TORCH_TCP), qa, qb


def test_the_roadmap_joins_what_a_straight_joint_motion_cannot_and_repeats_with_its_seed(robot):
    chk, qa, qb = plate_scene(robot)
    assert not chk.motion_free(qa, qb)
    det = Detour(robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 1.0, 0, tuck=())
    keep = int(robot.branch_bits(qa)[0])
    paths = []
    for _ in range(2):
        rm = branch_roadmap(det, np.array([qa, qb]), keep, SMALL, 3)
        ca, cb = rm.connect(np.array([qa, qb]))
        assert ca == cb >= 0
        paths.append(rm.path(qa, qb))
        rm.close()
    P = paths[0]
    np.testing.assert_array_equal(paths[1], P)  # the same seed, the same roadmap and path
    np.testing.assert_array_equal(P[0], qa)
    np.testing.assert_array_equal(P[-1], qb)
    assert len(P) >= 3
    # independent of the roadmap's motion proof: dense states of every edge, on the branch
    for a, b in zip(P[:-1], P[1:], strict=True):
        X = a + np.linspace(0.0, 1.0, 120)[:, None] * (b - a)
        assert all(chk.state_free(x) for x in X)
        assert (robot.branch_bits(X) == keep).all()


def test_a_detour_takes_the_roadmaps_path_and_reports_a_leg_it_does_not_join(robot):
    chk, qa, qb = plate_scene(robot)
    lr = LegRoadmap(np.array([qa, qb]), ("a", "b"), SMALL, 3)
    det = Detour(robot, chk, np.zeros((0, 4, 4)), TORCH_TCP, 5.0, "rrtconnect", 1e-3, 0,
                 tuck=(), roadmap=lr)  # fmt: skip
    P = det.transfer(qa, qb)
    assert P is not None and chk.path_hits(P) == []
    assert det.ompl["roadmap_joined"] == 1 and "runs" not in det.ompl  # OMPL not asked
    # an end inside the plate: not free, so no roadmap vertex; reported, one bounded OMPL run
    inside = qa.copy()
    inside[0] = 0.0
    assert not chk.state_free(inside)
    assert det.transfer(qa, inside) is None
    assert len(det.roadmap_misses) == 1 and "near weld" in det.roadmap_misses[0]
    assert det.ompl["runs"] == 1 and det.ompl.get("retries", 0) == 0
    lr.close()


def wall_station(robot):
    """Two welds 2.6 m from base A, at A1 = +-170 deg, and a wall in front of A (x 700-900 mm).
    With A2 kept within -60..-5 deg (upper arm leaning forward) every configuration at A1 = 0
    puts the elbow past x = 1000 mm, into the wall, and A1 cannot pass +-185 deg: from A the two
    welds are in two components of the joint space, exactly. Base B, 5.2 m behind A, has both
    welds in front (A1 = +-10 deg) and the straight motion between them free."""
    lo, hi = robot.lower.copy(), robot.upper.copy()
    lo[1], hi[1] = np.radians(-60.0), np.radians(-5.0)
    arm = dataclasses.replace(robot, lower=lo, upper=hi)
    wall = trimesh.creation.box([200.0, 8000.0, 6000.0]).apply_translation([800.0, 0.0, 1000.0])
    ang = np.radians([170.0, 180.0, -170.0])  # weld, waypoint, weld
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, :3, :3] = np.diag([1.0, -1.0, -1.0])  # the torch pointing down
    T[:, 0, 3], T[:, 1, 3], T[:, 2, 3] = 2600 * np.cos(ang), 2600 * np.sin(ang), 500.0
    A = base_pose(0.0, 0.0, 0.0, 0.0)
    B = base_pose(-5171.0, 0.0, 0.0, 0.0)
    chk = RobotCollision(arm, wall, arc_torch(), TORCH_TCP)
    return arm, chk, T @ np.linalg.inv(TORCH_TCP), A, B


def test_the_base_that_reaches_as_well_but_cannot_join_its_welds_loses_to_the_one_that_can(
    robot, caplog
):
    arm, chk, T_fl, A, B = wall_station(robot)
    rows = np.array([0, 2])
    cands = [Placement(A, 2, 2, 0.0, 2, True), Placement(B, 2, 2, 0.0, 2, True)]
    by_reach = PlacementSettings(trial=False)
    plain, _ = rank_bases(arm, cands, [None, None], T_fl, rows, chk.with_robot, by_reach)
    np.testing.assert_array_equal(plain.base, A)  # by reach and manipulability, A first
    tiny = RoadmapSettings(milestones=5, neighbours=4, query_neighbours=4)
    with caplog.at_level(logging.INFO, logger="weldplan.robot.placement.base"):
        best, _ = rank_bases(
            arm, cands, [None, None], T_fl, rows, chk.with_robot,
            PlacementSettings(joins=tiny), ids=("w1", "w2"),
        )  # fmt: skip
    np.testing.assert_array_equal(best.base, B)
    assert best.join.n_joined == 2 and best.join.blocked_legs == 0
    assert "base 0,0,0,0.0: 1/2 served welds joined (1 blocked legs" in caplog.text


def test_the_transfer_trial_alone_rejects_the_base_whose_welds_no_planner_free_move_joins(
    robot, caplog
):
    """The default step 4, no roadmap: from A the leg's own motion and every straight or tucked
    transfer between the retracts hit the wall (the welds are in two components of the joint
    space, wall_station), so A joins 1 of its 2 welds and says which leg splits and why; B
    joins both."""
    arm, chk, T_fl, A, B = wall_station(robot)
    rows = np.array([0, 2])
    cands = [Placement(A, 2, 2, 0.0, 2, True), Placement(B, 2, 2, 0.0, 2, True)]
    with caplog.at_level(logging.INFO, logger="weldplan.robot.placement.base"):
        best, _ = rank_bases(
            arm, cands, [None, None], T_fl, rows, chk.with_robot, PlacementSettings(),
            ids=("w1", "w2"),
        )  # fmt: skip
    np.testing.assert_array_equal(best.base, B)
    assert best.join.n_joined == 2 and best.join.splits == () and best.join.report is None
    assert (
        "base 0,0,0,0.0: 1/2 served welds joined (1 blocked legs; split w1 -> w2: its own "
        "motion blocked" in caplog.text
    )
    # the judgement at A on its own: the split leg named, no roadmap built
    rb = arm.with_base(A)
    det = Detour(rb, chk.with_robot(rb), T_fl @ TORCH_TCP, TORCH_TCP, 5.0, "rrtconnect", 1.0, 0)
    q, branch, _, status = joint_path(rb, T_fl, singular_deg=5.0, flip_penalty=1000.0)
    assert list(status[rows]) == ["ok", "ok"]
    wj = join_welds(det, q, branch, rows, np.ones(2, dtype=bool), None, ids=("w1", "w2"))
    assert wj.n_joined == 1 and wj.report is None and wj.roadmap is None
    assert len(wj.splits) == 1 and wj.splits[0].startswith("w1 -> w2: its own motion blocked")
    assert wj.summary()["split_legs"] == list(wj.splits)
    # the reach stage says it at once, with the base
    from weldplan.station.robotstage import _warn_splits

    with caplog.at_level(logging.WARNING, logger="weldplan.station.robotstage"):
        _warn_splits(dataclasses.replace(cands[0], join=wj))
    assert "base (0, 0, 0) yaw 0.0 deg: 1 of 2 served welds joined in one group" in caplog.text
    assert "OMPL): w1 -> w2: its own motion blocked" in caplog.text


def test_stands_turned_about_a1_tie_and_the_order_of_the_candidates_decides(robot):
    """The same stand turned 30 deg about its A1 axis: the welds' configurations differ only in
    A1, so the manipulability is the same but for round-off, and the first candidate wins
    whichever it is (before, the last bits of the sum chose, as they may differ by machine)."""
    ang = np.radians([20.0, 0.0, -20.0])
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, :3, :3] = np.diag([1.0, -1.0, -1.0])  # the torch pointing down
    T[:, 0, 3], T[:, 1, 3], T[:, 2, 3] = 1800 * np.cos(ang), 1800 * np.sin(ang), 600.0
    T_fl, rows = T @ np.linalg.inv(TORCH_TCP), np.array([0, 2])
    A, B = base_pose(0.0, 0.0, 0.0, 0.0), base_pose(0.0, 0.0, 0.0, 30.0)
    by_reach = PlacementSettings(trial=False)
    for first, second in ((A, B), (B, A)):
        cands = [Placement(first, 2, 2, 0.0, 2, True), Placement(second, 2, 2, 0.0, 2, True)]
        best, _ = rank_bases(robot, cands, [None, None], T_fl, rows, None, by_reach)
        np.testing.assert_array_equal(best.base, first)
        assert best.min_manipulability > 0.0


def test_each_judged_base_says_which_welds_it_leaves_out_and_the_summary_names_them(robot):
    """Step 4's verdicts (Placement.verdicts): at A the trial joins one of the two welds and
    names the other and the split leg; B joins both; the summary rows say it per base."""
    from weldplan.robot.placement.base import BaseVerdict
    from weldplan.station.summary import base_trial_rows

    arm, chk, T_fl, A, B = wall_station(robot)
    rows = np.array([0, 2])
    cands = [Placement(A, 2, 2, 0.0, 2, True), Placement(B, 2, 2, 0.0, 2, True)]
    best, _ = rank_bases(
        arm, cands, [None, None], T_fl, rows, chk.with_robot, PlacementSettings(),
        ids=("w1", "w2"),
    )  # fmt: skip
    at_a, at_b = best.verdicts
    assert at_a.base == pytest.approx((0.0, 0.0, 0.0, 0.0))
    assert (at_a.served, at_a.joined, at_a.unserved) == (2, 1, ())
    assert len(at_a.left_out) == 1 and at_a.left_out[0] in ("w1", "w2")
    assert len(at_a.splits) == 1 and at_a.splits[0].startswith("w1 -> w2: ")
    assert (at_b.served, at_b.joined, at_b.left_out, at_b.splits) == (2, 2, (), ())
    assert at_a.summary()["left_out"] == at_a.left_out
    rows_said = dict(base_trial_rows(best))
    assert rows_said["base trial"].startswith("1 of the 2 base(s) judged join all 2 welds")
    assert rows_said["  base 0,0,0,0.0"].startswith(
        f"1 of 2 served welds joined; left out: {at_a.left_out[0]}; split w1 -> w2: "
    )
    assert rows_said["  base -5171,0,0,0.0"] == "2 of 2 served welds joined"
    # the same order whichever comes first: A is first by manipulability, and B, serving more
    # welds than A joins, is judged too
    again, _ = rank_bases(
        arm, cands[::-1], [None, None], T_fl, rows, chk.with_robot, PlacementSettings(),
        ids=("w1", "w2"),
    )  # fmt: skip
    assert again.verdicts == best.verdicts
    skipped = BaseVerdict((0.0, 0.0, 0.0, 0.0), 1, -1, ("w2",), ())
    assert skipped.line() == "serves 1: not judged (no more than a base judged before joins)"


def test_step_four_judges_one_candidate_per_floor_position_before_a_second():
    """_by_stand: the heights and yaws of a stand after the first candidate of every other."""
    from weldplan.robot.placement.base import _by_stand

    at = [(0, 0, 0, 0), (0, 0, 0, 30), (0, 0, 400, 0), (250, 0, 0, 0), (0, 250, 0, 0)]
    cands = [Placement(base_pose(*p), 2, 2, 0.0, 5, True) for p in at]
    assert _by_stand(cands, [0, 1, 2, 3, 4]) == [0, 3, 4, 1, 2]
    assert _by_stand(cands, [2, 4, 1, 0, 3]) == [2, 4, 3, 1, 0]
