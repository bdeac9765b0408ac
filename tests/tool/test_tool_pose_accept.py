"""The pose search's acceptance test (weldplan.tool.poses.choice): vetoes, fallback, notes."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from weldplan.io.joints import Joints
from weldplan.tool import PoseSearchSettings, WeldPoses, arc_torch, plan_weld_poses, verify_poses
from weldplan.tool.poses import rotation_angles


def _plate() -> trimesh.Trimesh:
    return trimesh.creation.box((600, 600, 2)).apply_translation((0, 0, -1))


def _up(*ids_xyz) -> Joints:
    ids = [i for i, _ in ids_xyz]
    xyz = [p for _, p in ids_xyz]
    return Joints(ids=ids, xyz=xyz, directions=[[0.0, 0.0, 1.0]] * len(ids))


def _tilt_deg(T: np.ndarray) -> float:
    """Degrees between the TCP z axis and straight down (the plate's approach axis)."""
    return math.degrees(math.acos(np.clip(-T[2, 2], -1.0, 1.0)))


def test_a_vetoed_pick_gives_way_to_the_next_least_rotation_pose():
    plate, torch = _plate(), arc_torch()
    welds = _up(("a", (0, 0, 0)), ("b", (100, 50, 0)))
    seen: list[tuple[int, float]] = []

    def accept(i: int, T: np.ndarray) -> str | None:
        seen.append((i, _tilt_deg(T)))
        return "untilted at a" if i == 0 and _tilt_deg(T) < 1.0 else None

    # 24 spins every 15 deg are untilted: up to 24 vetoes before a tilt is tried
    poses = plan_weld_poses(plate, welds, torch, PoseSearchSettings(max_vetoes=30), accept=accept)
    a, b = poses.poses
    assert a.ok and b.ok and not a.note and not b.note
    # a is tilted by the first ring (7.5 deg), and b, free to, follows it: no rotation between
    assert a.tilt == pytest.approx(7.5) and b.tilt == pytest.approx(7.5)
    assert poses.total_rotation == pytest.approx(0.0, abs=1e-6)
    assert rotation_angles([a.quaternion], [b.quaternion])[0, 0] == pytest.approx(0.0, abs=1e-6)
    # every pick was judged once, and no veto survived into the answer
    vetoed = [t for i, t in seen if i == 0 and t < 1.0]
    assert poses.stats["vetoed"] == len(vetoed) >= 1 and poses.stats["accept_exhausted"] == 0
    assert poses.stats["accept_calls"] == len(seen)
    assert verify_poses(poses, plate, torch).ok


def test_a_weld_whose_every_free_pose_is_vetoed_keeps_its_best_free_pose_with_a_note():
    plate, torch = _plate(), arc_torch()
    welds = _up(("a", (0, 0, 0)), ("b", (100, 50, 0)))
    plain = plan_weld_poses(plate, welds, torch)
    poses = plan_weld_poses(
        plate, welds, torch, PoseSearchSettings(max_vetoes=3),
        accept=lambda i, T: "no exit" if i == 1 else None,
    )  # fmt: skip
    assert [p.quaternion for p in poses.poses] == [p.quaternion for p in plain.poses]
    a, b = poses.poses
    assert b.ok and b.note.startswith("3 free poses vetoed (no exit)")
    assert not a.note and poses.stats["accept_exhausted"] == 1 and poses.stats["vetoed"] == 3
    assert "weld b: 3 free poses vetoed" in poses.summary()
    back = WeldPoses.from_json(poses.to_json())
    assert back.poses[1].note == b.note


def test_an_accept_that_passes_everything_changes_nothing():
    plate, torch = _plate(), arc_torch(bend_angle=30.0)
    welds = _up(("a", (0, 0, 0)), ("b", (100, 50, 0)), ("c", (-80, 120, 0)))
    plain = plan_weld_poses(plate, welds, torch)
    poses = plan_weld_poses(plate, welds, torch, accept=lambda i, T: None)
    assert [p.quaternion for p in poses.poses] == [p.quaternion for p in plain.poses]
    assert poses.stats["accept_calls"] == 3 and poses.stats["vetoed"] == 0


def test_accept_sees_the_tcp_pose_of_the_pick():
    plate, torch = _plate(), arc_torch()
    got: dict[int, np.ndarray] = {}

    def accept(i: int, T: np.ndarray) -> None:
        got[i] = T

    poses = plan_weld_poses(plate, _up(("a", (10, 20, 0))), torch, accept=accept)
    (p,) = poses.poses
    T = got[0]
    np.testing.assert_allclose(T[:3, 3], p.position)
    np.testing.assert_allclose(T[:3, :3], p.rotation(), atol=1e-9)
    np.testing.assert_allclose(T[3], [0, 0, 0, 1])


def test_all_of_vetoes_with_the_first_test_that_vetoes_and_skips_the_rest():
    from weldplan.tool.poses import all_of

    calls: list[str] = []

    def t(name: str, verdict: str | None):
        def f(i: int, T: np.ndarray) -> str | None:
            calls.append(name)
            return verdict

        return f

    assert all_of() is None and all_of(None, None) is None
    one = t("x", None)
    assert all_of(None, one) is one
    both = all_of(t("a", None), None, t("b", "no exit"), t("c", "unreached"))
    assert both(0, np.eye(4)) == "no exit" and calls == ["a", "b"]
    assert all_of(t("a", None), t("b", None))(0, np.eye(4)) is None
