"""Completeness of the gun pose search: wherever the dense oracle (weldplan.bench.gun_oracle)
finds a free pose of the shared C-gun on a sheet-metal spot, plan_weld_poses finds one too."""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import require_shared
from weldplan.bench.gun_oracle import (
    GunOracle,
    OracleSettings,
    completeness,
    frame_settings,
    orientation_grid,
    tool_outside_sphere,
)
from weldplan.io.joints import Joints
from weldplan.tool import plan_weld_poses, shared_spot_gun
from weldplan.tool.poses import quat_wxyz
from weldplan.tool.verify import PoseChecker
from weldplan.weld.sheetmetal import generate_side_frame


@pytest.fixture(scope="module")
def gun():
    return shared_spot_gun(require_shared("tools", "spot_welding_gun"))


def _subset(joints: Joints, idx) -> Joints:
    idx = list(idx)
    return Joints(
        ids=tuple(joints.ids[i] for i in idx),
        xyz=joints.xyz[idx],
        directions=joints.directions[idx],
    )


def test_orientation_grid_is_dense_inside_the_cone():
    s = OracleSettings()
    axis = np.array([0.3, -0.5, 0.8])
    axis /= np.linalg.norm(axis)
    R = orientation_grid(axis, s)
    assert len(R) == 72 * (1 + 3 * 24)
    np.testing.assert_allclose(
        np.einsum("kji,kjl->kil", R, R), np.tile(np.eye(3), (len(R), 1, 1)), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(R), 1.0)
    tilt = np.degrees(np.arccos(np.clip(R[:, :, 2] @ axis, -1, 1)))
    assert tilt.max() <= 15.0 + 1e-9
    assert sorted(set(np.round(tilt, 3))) == pytest.approx([0.0, 5.0, 10.0, 15.0])
    x = R[:72, :, 0]  # the untilted spins: the x axis turns 5 deg a step about the axis
    step = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", x, np.roll(x, -1, axis=0)), -1, 1)))
    np.testing.assert_allclose(step, 5.0, atol=1e-9)


def test_oracle_cut_of_the_gun_agrees_with_the_tool_model(gun):
    """Two independent cuts of the gun by the 20 mm contact sphere (0.5 mm and 1 mm edges):
    nothing wholly inside the sphere is kept, and they keep the same area to the resolution."""
    v, f = tool_outside_sphere(gun.vertices, gun.faces, 20.0)
    tri = v[f]
    assert not np.any(np.all(np.linalg.norm(tri, axis=2) <= 20.0, axis=1))
    mv, mf = gun.outside_zone(20.0)
    a_oracle = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    t2 = mv[mf]
    a_model = np.linalg.norm(np.cross(t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0]), axis=1).sum()
    assert a_oracle <= a_model  # finer edges reach less far into the sphere
    assert a_oracle == pytest.approx(a_model, rel=2e-3)


def test_search_finds_a_pose_wherever_the_oracle_does_small(gun):
    """Fast version: 5 spots of the default frame and a spot on the crown (a wide plate, no
    free edge within the C's throat): the verdicts agree, and the oracle's pose passes the
    project's independent re-check."""
    st = generate_side_frame(rng=0)
    part = st.combined()
    sub = _subset(st.spots, range(0, len(st.spots), 60))
    crown = Joints(ids=("crown",), xyz=[[1000.0, 51.5, 81.5]], directions=[[0.0, 1.0, 0.0]])
    joints = Joints(
        ids=sub.ids + crown.ids,
        xyz=np.vstack([sub.xyz, crown.xyz]),
        directions=np.vstack([sub.directions, crown.directions]),
    )
    c = completeness(part, joints, gun)
    assert c.oracle == (True,) * len(sub) + (False,)
    assert c.misses == ()
    assert c.search[-1] is False  # the search does not find what is not there either
    oracle = GunOracle(part, gun)
    checker = PoseChecker(part, gun, 20.0, 5.0)
    for p, d in zip(sub.xyz, sub.directions, strict=True):
        a = oracle.closes(p, -d)
        assert checker.check(p, quat_wxyz(a.rotation[None])[0]).ok


@pytest.mark.slow
def test_search_finds_a_pose_wherever_the_oracle_does(gun):
    """Issue 29, item 5: at least 100 spots of the generated side frame (every other spot of
    its 241: all three members)."""
    st = generate_side_frame(rng=0)
    c = completeness(st.combined(), _subset(st.spots, range(0, len(st.spots), 2)), gun)
    assert sum(c.oracle) >= 100
    assert c.misses == (), f"oracle closes, search does not: {c.misses}"


#: the two misses on the deep frame at seed 1: spots of the sill's upper flange either side of
#: the B-pillar's foot, where the oracle's free frame tilts 15 deg about 15 deg off the sill's
#: axis (between the search's tilt azimuths, every 45 deg)
DEEP_MISSES = ("sill_a-28", "sill_a-30")


@pytest.fixture(scope="module")
def deep_frame():
    """The deep frame at seed 1 (``frame_settings("deep")``)."""
    st = generate_side_frame(frame_settings("deep", None), rng=1)
    return st.combined(), st.spots


@pytest.mark.parametrize("spot", DEEP_MISSES)
def test_oracle_closes_on_the_deep_frame_misses(gun, deep_frame, spot):
    part, spots = deep_frame
    i = spots.index(spot)
    p, d = spots.xyz[i], spots.directions[i]
    a = GunOracle(part, gun).closes(p, -d)
    assert a.free and not a.flipped
    tilt = np.degrees(np.arccos(np.clip(a.rotation[:, 2] @ -d, -1, 1)))
    assert tilt == pytest.approx(15.0)
    assert PoseChecker(part, gun, 20.0, 5.0).check(p, quat_wxyz(a.rotation[None])[0]).ok


@pytest.mark.xfail(
    strict=True,
    reason="completeness misses of tool/poses/search (reported, not fixed here): the oracle's "
    "verified frame tilts 15 deg at an azimuth between the search's 8 (every 45 deg)",
)
@pytest.mark.parametrize("spot", DEEP_MISSES)
def test_search_closes_on_the_deep_frame_misses(gun, deep_frame, spot):
    part, spots = deep_frame
    assert plan_weld_poses(part, _subset(spots, [spots.index(spot)]), gun).poses[0].ok


def test_weldplan_bench_gun_oracle_writes_its_table(gun, tmp_path, capsys):
    from weldplan.cli import main

    rc = main(
        ["bench", "gun-oracle", "--frames", "default", "--spots", "4", "--out", str(tmp_path)]
    )
    assert rc == 0
    rows = [
        r
        for r in (tmp_path / "gun_oracle.md").read_text().splitlines()
        if r.startswith("| default")
    ]
    assert len(rows) == 1
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    n, oracle, search = (int(c) for c in cells[1:4])
    assert n >= 4 and 0 < oracle <= n and 0 < search <= n
    assert cells[4].startswith(f"{oracle} (") and cells[5] == "-"  # the search misses none
