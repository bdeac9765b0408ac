"""The exit test of the pose search (weldplan.tool.poses.exits): a pose the tool can leave."""

from __future__ import annotations

import dataclasses
from dataclasses import replace

import numpy as np
import pytest
import trimesh

from weldplan.io.joints import Joints
from weldplan.tool import (
    PoseSearchSettings,
    Tool,
    TransitionSettings,
    plan_weld_poses,
    verify_poses,
)
from weldplan.tool.poses import ExitTest
from weldplan.tool.transitions import TransitionPlanner, plan_transitions
from weldplan.tool.verify import verify_sweeps


def _box(extents, centre) -> trimesh.Trimesh:
    return trimesh.creation.box(extents).apply_translation(centre)


def _stick(straddles: bool = False) -> Tool:
    """A 10 mm square stick 200 mm long behind the TCP (along TCP -z), its tip face at the TCP."""
    m = _box((10, 10, 200), (0, 0, -100))
    return Tool("stick", np.asarray(m.vertices), np.asarray(m.faces), straddles=straddles)


def _capped_plate() -> trimesh.Trimesh:
    """A plate (top face z = 0) and a 30 x 30 mm cap 215-225 mm above the spot at the origin:
    the stick standing straight up on the spot (top at z = 200) clears the cap by 15 mm, but
    its axial retract (50 mm up) runs into it; tilted 7.5 deg the stick passes beside it."""
    return trimesh.util.concatenate(
        [_box((600, 600, 2), (0, 0, -1)), _box((30, 30, 10), (0, 0, 220))]
    )


def _welds() -> Joints:
    # a under the cap, b 150 mm away with nothing above it; both approached from above
    return Joints(ids=["a", "b"], xyz=[[0, 0, 0], [150, 0, 0]], directions=[[0, 0, 1.0]] * 2)


#: the axial retract only: no side exit, no SE(3) re-plan
AXIAL = TransitionSettings(retract=50.0, side_exit=0.0, se3=False)
#: room for the 24 untilted spins' vetoes
VETOES_30 = PoseSearchSettings(max_vetoes=30)


def _planner(part: trimesh.Trimesh, tool: Tool) -> TransitionPlanner:
    # side exits off: under this cap a 5 mm lift and a sideways exit would leave every pose
    return TransitionPlanner(part, tool, AXIAL, clearance=5.0, contact_radius=20.0)


def test_a_pose_without_an_exit_gives_way_to_the_least_rotation_pose_with_one():
    part, stick = _capped_plate(), _stick()
    plain = plan_weld_poses(part, _welds(), stick)
    a0 = plain.poses[0]
    assert a0.ok and a0.tilt == 0.0 and a0.spin == 0.0  # straight up: free, but no way out
    planner = _planner(part, stick)
    ok, why = planner.exit_free(a0)
    assert not ok and why.startswith("axial retract: retract blocked")

    test = ExitTest(planner, ["a", "b"])
    # the 24 untilted spins all retract into the cap (as many vetoes at most)
    poses = plan_weld_poses(part, _welds(), stick, VETOES_30, accept=test)
    a, b = poses.poses
    assert a.ok and b.ok and not a.note and not b.note
    # the first candidate past the untilted ones: the first ring (7.5 deg), first direction,
    # spin 0; b follows it exactly (no rotation between the two)
    assert (a.tilt, a.azimuth, a.spin, a.flipped) == (7.5, 0.0, 0.0, False)
    assert (b.tilt, b.azimuth, b.spin) == (7.5, 0.0, 0.0)
    assert poses.total_rotation == pytest.approx(0.0, abs=1e-6)
    assert 1 <= test.vetoes == poses.stats["vetoed"] <= 24 and test.how == {
        "a": "axial retract",
        "b": "axial retract",
    }
    assert planner.exit_free(a) == (True, "axial retract")
    assert verify_poses(poses, part, stick).ok


def test_a_weld_with_no_exit_in_its_vetoes_keeps_its_least_rotation_pose_with_a_note():
    part, stick = _capped_plate(), _stick()
    plain = plan_weld_poses(part, _welds(), stick)
    poses = plan_weld_poses(part, _welds(), stick, accept=ExitTest(_planner(part, stick), "ab"))
    # 12 vetoes (the default cap), all untilted: the test is lifted for a, which keeps the pose
    # it had without the test, and says why
    assert [p.quaternion for p in poses.poses] == [p.quaternion for p in plain.poses]
    a = poses.poses[0]
    assert a.note.startswith("12 free poses vetoed (no exit: axial retract: retract blocked")
    assert poses.stats["accept_exhausted"] == 1 and not poses.poses[1].note


def test_a_straddling_tool_turns_over_when_no_pose_on_the_approach_side_is_accepted():
    plate = _box((600, 600, 2), (0, 0, -1))
    gun = _stick(straddles=True)
    welds = Joints(ids=["a"], xyz=[[0, 0, 0]], directions=[[0, 0, 1.0]])

    def from_below_only(i: int, T: np.ndarray) -> str | None:
        return "from above" if T[2, 2] < 0 else None  # TCP +z down: the approach side

    poses = plan_weld_poses(plate, welds, gun, accept=from_below_only)
    (a,) = poses.poses
    # every free pose from above vetoed (12 of them), then the turned-over ones: the first
    # free one is accepted
    assert a.ok and a.flipped and not a.note and (a.tilt, a.spin) == (0.0, 0.0)
    assert poses.stats["vetoed"] == 12 and poses.stats["turned_over_tried"] == 1
    assert a.rotation()[2, 2] == pytest.approx(1.0)

    # vetoed on both sides: the approach side stays the first choice, with a note
    never = plan_weld_poses(plate, welds, gun, accept=lambda i, T: "never")
    (n,) = never.poses
    assert n.ok and not n.flipped and n.note.startswith("24 free poses vetoed (never)")
    assert n.quaternion == plan_weld_poses(plate, welds, gun).poses[0].quaternion


def test_the_transitions_reuse_the_exits_the_test_checked():
    part, stick = _capped_plate(), _stick()
    planner = _planner(part, stick)
    test = ExitTest(planner, ["a", "b"])
    poses = plan_weld_poses(part, _welds(), stick, VETOES_30, accept=test)
    assert test.samples > 0
    n_before = planner.samples
    reused = plan_transitions(part, stick, poses, reuse=planner)  # the planner's settings
    fresh = plan_transitions(part, stick, poses, AXIAL)
    (t,) = reused.transitions
    (f,) = fresh.transitions
    assert t.kinds == f.kinds == ("retract", "move", "approach") and t.free
    np.testing.assert_array_equal(t.positions, f.positions)
    # both retracts were checked by the test: only the move is sampled again
    assert 0 < reused.stats["samples"] == planner.samples - n_before < fresh.stats["samples"]
    assert verify_sweeps(reused, poses, part, stick).ok
    # a planner with other settings is refused
    with pytest.raises(ValueError, match="retract"):
        plan_transitions(part, stick, poses, replace(AXIAL, retract=30.0), reuse=planner)
    other = dataclasses.replace(stick, _cache={})
    with pytest.raises(ValueError, match="part or tool"):
        plan_transitions(part, other, poses, AXIAL, reuse=planner)


def test_the_tool_order_prices_a_weld_left_by_a_lift_at_the_lift():
    from weldplan.tool.poses import leave_distances
    from weldplan.tool.transitions import tool_leg_costs

    plate, gun = _box((600, 600, 2), (0, 0, -1)), _stick(straddles=True)
    welds = Joints(ids=["a", "b", "c"], xyz=[[0, 0, 0], [150, 0, 0], [0, 120, 0]],
                   directions=[[0, 0, 1.0]] * 3)  # fmt: skip
    no_se3 = TransitionSettings(se3=False)
    planner = TransitionPlanner(plate, gun, no_se3, clearance=5.0, contact_radius=20.0)
    poses = plan_weld_poses(plate, welds, gun, accept=ExitTest(planner, welds.ids))
    assert all(p.ok and not p.flipped and p.tilt == 0.0 for p in poses.poses)
    # a C-gun leaves each weld by the first slide lift (4 mm), found by the test and cached
    leave = leave_distances(planner, poses)
    assert leave == {"a": 4.0, "b": 4.0, "c": 4.0}
    ids = ["a", "b", "c"]
    _, axial, _ = tool_leg_costs(poses, ids, 50.0, 200.0)
    _, lifted, _ = tool_leg_costs(poses, ids, 50.0, 200.0, {"a": 4.0, "b": 4.0})
    # same orientation everywhere: the retract points are the spots moved alike
    assert axial[0, 1] == pytest.approx(150.0 + 100.0)
    assert lifted[0, 1] == pytest.approx(150.0 + 8.0)
    assert (
        lifted[0, 2]
        == pytest.approx(lifted[2, 0])
        == pytest.approx(
            np.hypot(120.0, 46.0) + 54.0  # a lifted 4 mm, c retracted 50 mm
        )
    )
