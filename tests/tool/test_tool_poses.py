"""Weld poses: free poses, closest misses, spin/tilt search, least-rotation DP, re-check, JSON."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from tests.conftest import require_shared
from weldplan.io.joints import Joints
from weldplan.tool import (
    PoseSearchSettings,
    WeldPoses,
    arc_torch,
    plan_weld_poses,
    shared_spot_gun,
    surface_approach,
    verify_poses,
)
from weldplan.tool.poses import least_rotation_choice, local_candidates, quat_wxyz, rotation_angles


def _box(extents, centre) -> trimesh.Trimesh:
    return trimesh.creation.box(extents).apply_translation(centre)


def _up(*ids_xyz) -> Joints:
    """Joints approached from above (direction from the joint towards the torch: +z)."""
    ids = [i for i, _ in ids_xyz]
    xyz = [p for _, p in ids_xyz]
    return Joints(ids=ids, xyz=xyz, directions=[[0.0, 0.0, 1.0]] * len(ids))


def test_open_flat_plate_is_free_and_verified():
    plate = _box((600, 600, 2), (0, 0, -1))
    torch = arc_torch()
    poses = plan_weld_poses(plate, _up(("a", (0, 0, 0)), ("b", (100, 50, 0))), torch)
    assert poses.n_ok == 2
    for p in poses.poses:
        R = p.rotation()
        np.testing.assert_allclose(R[:, 2], [0, 0, -1], atol=math.sin(math.radians(15.01)))
        assert p.miss is None
    assert verify_poses(poses, plate, torch).ok
    # untilted and the same spin: no rotation between the two welds
    assert poses.total_rotation == pytest.approx(0.0, abs=1e-6)


def test_narrow_slot_has_no_free_pose_and_reports_the_hitting_region():
    # a 16 mm wide, 100 mm deep slot: the 25 mm nozzle cannot enter at any spin or tilt
    part = trimesh.util.concatenate(
        [
            _box((300, 300, 2), (0, 0, -1)),
            _box((300, 20, 100), (0, 18, 50)),
            _box((300, 20, 100), (0, -18, 50)),
        ]
    )
    torch = arc_torch(bend_angle=0.0)
    poses = plan_weld_poses(
        part, _up(("slot", (0, 0, 0))), torch, PoseSearchSettings(contact_radius=10.0)
    )
    (p,) = poses.poses
    assert not p.ok and p.quaternion is None
    assert p.miss is not None and p.miss.contacts > 0 and p.miss.penetration > 0
    # the nozzle or neck hits: behind the TCP, on its outer wall, no higher than the walls
    x, y, z = p.miss.tool_point
    assert -100.0 <= z < 0 and math.hypot(x, y) == pytest.approx(12.5, abs=1.0)
    assert "behind the TCP" in p.miss.region and "no free pose" in poses.summary()
    assert verify_poses(poses, part, torch).checked == 0


def test_spin_and_tilt_search_finds_the_one_free_orientation():
    # a ceiling with a hole that only the bent neck at spin 90 deg, untilted, passes through
    b = math.radians(30.0)
    h = 75.0 + 100.0 * math.cos(b)  # the neck's height 100 mm past the bend
    hole = (0.0, 100.0 * math.sin(b))  # where spin 90 puts it (frame x0 = +x, y0 = -y)
    hx, hy, size = 15.0, 17.0, 400.0
    t = 2.0
    cx, cy = hole
    ceiling = trimesh.util.concatenate(
        [
            _box((size, size, t), (cx, cy + hy + size / 2, h)),
            _box((size, size, t), (cx, cy - hy - size / 2, h)),
            _box((size, 2 * hy, t), (cx + hx + size / 2, cy, h)),
            _box((size, 2 * hy, t), (cx - hx - size / 2, cy, h)),
        ]
    )
    torch = arc_torch(bend_angle=30.0, neck_length=150.0)
    poses = plan_weld_poses(
        ceiling, _up(("w", (0, 0, 0))), torch, PoseSearchSettings(clearance=0.0)
    )
    (p,) = poses.poses
    assert p.ok and p.n_collision_free == 1
    assert (p.spin, p.tilt) == (90.0, 0.0)
    assert verify_poses(poses, ceiling, torch).ok


def test_least_rotation_dp_matches_brute_force():
    rng = np.random.default_rng(3)
    stages = [Rotation.random(k, random_state=rng).as_quat() for k in (3, 4, 2, 4, 3)]
    choice, total = least_rotation_choice(stages)
    best = math.inf
    for combo in itertools.product(*(range(len(s)) for s in stages)):
        cost = sum(
            rotation_angles(stages[i][combo[i]][None], stages[i + 1][combo[i + 1]][None])[0, 0]
            for i in range(len(stages) - 1)
        )
        best = min(best, cost)
    assert total == pytest.approx(best, rel=1e-12)
    chosen = sum(
        rotation_angles(stages[i][choice[i]][None], stages[i + 1][choice[i + 1]][None])[0, 0]
        for i in range(len(stages) - 1)
    )
    assert chosen == pytest.approx(total, rel=1e-12)
    # a greedy choice from the cheapest first step is worse here, so the DP is doing the work
    g = [int(np.argmin(rotation_angles(stages[0], stages[1]).min(axis=1)))]
    for i in range(1, len(stages)):
        g.append(int(np.argmin(rotation_angles(stages[i - 1][g[-1]][None], stages[i])[0])))
    greedy = sum(
        rotation_angles(stages[i][g[i]][None], stages[i + 1][g[i + 1]][None])[0, 0]
        for i in range(len(stages) - 1)
    )
    assert greedy > total + 1.0


def test_candidates_cover_spins_and_tilt_rings():
    local, params = local_candidates(15.0, 7.5, 15.0, 8)
    assert len(local) == 24 * (1 + 2 * 8)
    z = local[:, :, 2]  # the tool axis of each candidate in the nominal frame
    tilt = np.degrees(np.arccos(np.clip(z[:, 2], -1, 1)))
    np.testing.assert_allclose(tilt, params[:, 1], atol=1e-9)
    np.testing.assert_allclose(np.linalg.det(local), 1.0, atol=1e-12)


def test_the_recheck_rejects_a_pose_that_hits():
    plate = _box((600, 600, 2), (0, 0, -1))
    torch = arc_torch()
    poses = plan_weld_poses(plate, _up(("a", (0, 0, 0))), torch)
    d = poses.to_dict()
    # lay the torch flat on the plate: the nozzle lies in the sheet
    flat = quat_wxyz(Rotation.from_euler("y", 90, degrees=True).as_matrix()[None])[0]
    d["poses"][0]["quaternion"] = flat.tolist()
    bad = WeldPoses.from_dict(d)
    out = verify_poses(bad, plate, torch)
    assert not out.ok and out.failures[0][0] == "a" and "outside" in out.failures[0][1]


def test_weld_poses_json_round_trip():
    part = trimesh.util.concatenate(
        [_box((300, 300, 2), (0, 0, -1)), _box((300, 20, 100), (0, 18, 50))]
    )
    joints = _up(("free", (0, -100, 0)), ("near", (0, 0, 0)))
    poses = plan_weld_poses(part, joints, arc_torch(), PoseSearchSettings(cone=0.0))
    assert [p.ok for p in poses.poses] == [True, False]
    again = WeldPoses.from_json(poses.to_json())
    assert again.to_dict() == poses.to_dict()
    assert again.poses[0] == poses.poses[0]  # the ok pose has no NaN fields
    assert again.poses[1].miss == poses.poses[1].miss and math.isnan(again.poses[1].spin)


def test_surface_normal_approach_when_the_csv_has_none():
    plate = _box((600, 600, 2), (0, 0, -1))
    axes = surface_approach(plate, [[10.0, 10.0, 0.0], [0.0, 0.0, -2.0]])
    np.testing.assert_allclose(axes, [[0, 0, -1], [0, 0, 1]], atol=1e-12)
    joints = Joints(ids=["a"], xyz=[[10.0, 10.0, 0.0]])
    poses = plan_weld_poses(plate, joints, arc_torch())
    assert poses.poses[0].ok
    np.testing.assert_allclose(poses.poses[0].approach, [0, 0, -1], atol=1e-12)


def test_gun_straddles_a_flange_but_not_the_middle_of_a_wide_plate():
    gun = shared_spot_gun(require_shared("tools", "spot_welding_gun"))
    # a 30 mm flange standing up from a floor far below, and a wide plate
    flange = _box((400, 2, 30), (0, 1, 15))  # face at y = 0, edge at z = 30
    spot = (0.0, 0.0, 20.0)  # 10 mm below the flange's edge, on its -y face
    j = Joints(ids=["f"], xyz=[spot], directions=[[0.0, -1.0, 0.0]])
    on_flange = plan_weld_poses(flange, j, gun)
    assert on_flange.poses[0].ok
    assert verify_poses(on_flange, flange, gun).ok
    plate = _box((1200, 2, 1200), (0, 1, 0))
    j = Joints(ids=["m"], xyz=[(0.0, 0.0, 0.0)], directions=[[0.0, -1.0, 0.0]])
    middle = plan_weld_poses(plate, j, gun, PoseSearchSettings(cone=0.0, spin_step=45.0))
    p = middle.poses[0]
    assert not p.ok and p.miss is not None and p.miss.contacts > 0
    assert p.miss.tool_point[2] > 0  # what hits is ahead of the TCP: the far side of the C


def test_triangle_crossings_are_the_ends_of_the_intersection_segment():
    from weldplan.tool.verify import triangle_crossings

    a = np.array([[-10.0, -10.0, 0.0], [10.0, -10.0, 0.0], [0.0, 10.0, 0.0]])
    b = np.array([[0.0, -5.0, -1.0], [0.0, 5.0, -1.0], [0.0, 0.0, 1.0]])  # plane x = 0
    P, ok = triangle_crossings(np.stack([a, a]), np.stack([b, b + [0.0, 0.0, 5.0]]))
    pts = P[0, ok[0]]
    # b's edges from the base to the apex cross z = 0 at y = -2.5 and y = 2.5
    np.testing.assert_allclose(sorted(pts[:, 1]), [-2.5, 2.5], atol=1e-12)
    np.testing.assert_allclose(pts[:, [0, 2]], 0.0, atol=1e-12)
    assert not ok[1].any()  # lifted 5 mm: b no longer reaches a's plane


def test_arc_torch_may_not_pass_through_a_sheet_near_the_spot():
    # a 1 mm shelf 17 mm above the spot, from x = 6 mm on: a straight nozzle (radius 12.5 mm,
    # mouth 15 mm above the spot) standing on the spot passes through it, 20-22 mm from the spot
    part = trimesh.util.concatenate(
        [_box((600, 600, 2), (0, 0, -1)), _box((200, 600, 1), (106, 0, 17.5))]
    )
    torch = arc_torch(bend_angle=0.0)
    joints = _up(("s", (0, 0, 0)))
    kw = PoseSearchSettings(cone=0.0, spin_step=90.0, contact_radius=25.0, clearance=2.0)
    # with the whole sphere exempt (a C-gun's contact zone) the nozzle through the shelf passes
    as_gun = dataclasses.replace(torch, tip_cone=None, _cache={})
    through = plan_weld_poses(part, joints, as_gun, kw)
    assert through.poses[0].ok
    # the torch's own zone is its tip cone: the nozzle wall is 35-40 deg off its axis
    poses = plan_weld_poses(part, joints, torch, kw)
    p = poses.poses[0]
    assert not p.ok and p.miss is not None and p.miss.contacts > 0
    assert 15.0 < p.miss.tool_point[2] * -1 < 25.0  # the nozzle's mouth, behind the TCP
    # and the independent re-check of the torch refuses the pose the sphere let through
    out = verify_poses(through, part, torch)
    assert not out.ok and "tip cone" in out.failures[0][1]


def test_gun_turns_over_when_the_approach_side_is_blocked():
    gun = shared_spot_gun(require_shared("tools", "spot_welding_gun"))
    flange = _box((400, 2, 30), (0, 1, 15))  # face at y = 0, edge at z = 30
    spot = (0.0, 0.0, 20.0)
    j = Joints(ids=["f"], xyz=[spot], directions=[[0.0, -1.0, 0.0]])  # torch on the -y side
    free = plan_weld_poses(flange, j, gun)
    assert free.poses[0].ok and not free.poses[0].flipped  # the approach side first
    # a wall 150 mm behind the TCP on the approach side blocks the gun's body there
    wall = _box((1200, 10, 1200), (0, -150, 0))
    part = trimesh.util.concatenate([flange, wall])
    one = plan_weld_poses(part, j, gun, PoseSearchSettings(both_sides=False))
    assert not one.poses[0].ok and one.poses[0].miss is not None
    both = plan_weld_poses(part, j, gun)
    p = both.poses[0]
    assert p.ok and p.flipped
    np.testing.assert_allclose(p.approach, [0.0, -1.0, 0.0], atol=1e-12)  # axis reversed
    assert p.rotation()[1, 2] < -math.cos(math.radians(15.01))  # TCP +z towards -y
    assert verify_poses(both, part, gun).ok
    # an arc torch does not straddle the sheet: it never turns over by default
    assert plan_weld_poses(part, j, arc_torch()).settings["both_sides"] is False


def test_shared_crops_and_the_whole_part_give_the_same_poses():
    # a long plate, a wall beside the second weld, a post far beyond the torch's reach
    part = trimesh.util.concatenate(
        [
            _box((2000, 400, 2), (500, 0, -1)),
            _box((200, 4, 120), (60, 30, 60)),
            _box((20, 20, 300), (1400, 0, 150)),
        ]
    )
    joints = _up(("a", (0, 0, 0)), ("b", (60, 0, 0)), ("c", (120, 0, 0)), ("d", (1300, 0, 0)))
    torch = arc_torch()
    cropped = plan_weld_poses(part, joints, torch, PoseSearchSettings(spin_step=30.0))
    whole = plan_weld_poses(part, joints, torch, PoseSearchSettings(spin_step=30.0, crop=False))
    # a, b share the crop made at a; c (120 mm from a) and d need their own
    assert cropped.stats["crops_built"] == 3 and whole.stats["crops_built"] == 0
    assert [p.status for p in cropped.poses] == [p.status for p in whole.poses]
    for p, q in zip(cropped.poses, whole.poses, strict=True):
        assert p.quaternion == q.quaternion and p.n_collision_free == q.n_collision_free
    assert cropped.total_rotation == whole.total_rotation
    # the wall blocks some of b's candidates: the crops held it
    assert 0 < cropped.poses[1].n_collision_free < cropped.stats["candidates_per_weld"]


def test_a_second_search_of_the_same_part_reuses_the_recheck_verdicts_and_gives_the_same_poses(
    monkeypatch,
):
    from weldplan.tool.poses import Rechecks
    from weldplan.tool.verify import PoseChecker

    plate = _box((600, 600, 2), (0, 0, -1))
    wall = _box((600, 4, 120), (0, 40, 60))  # near weld b: some picks fall short, some pass
    part = trimesh.util.concatenate([plate, wall])
    torch = arc_torch()
    welds = _up(("a", (0, -60, 0)), ("b", (50, 20, 0)), ("c", (-80, -120, 0)))
    asked = []
    real = PoseChecker.check

    def counted(self, p, q):
        asked.append(1)
        return real(self, p, q)

    monkeypatch.setattr(PoseChecker, "check", counted)
    first = plan_weld_poses(part, welds, torch)
    n_first = len(asked)
    again = plan_weld_poses(part, welds, torch)
    n_again = len(asked) - n_first
    # another part (even an equal one) is another re-check
    other = plan_weld_poses(part.copy(), welds, torch)
    n_other = len(asked) - n_first - n_again
    assert first.n_ok == 3 and n_first >= 3
    assert n_again == 0 and n_other == n_first
    for x, y, z in zip(first.poses, again.poses, other.poses, strict=True):
        assert x.quaternion == y.quaternion == z.quaternion
    assert Rechecks.of(part, torch, 20.0, 5.0) is Rechecks.of(part, torch, 20.0, 5.0)
    assert verify_poses(again, part, torch).ok
