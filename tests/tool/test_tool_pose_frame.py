"""Tool poses do not depend on how the part is turned in the cell (issue 30; tool/poses/orient.py
``nominal_frames``): the candidates' frames are built from the part's own axes, so the same
part and welds placed at another yaw give the same poses turned with the part. Checked on the
box scene (tests/route_fixtures.py: a wall on a floor plate) with the bent arc torch, whose neck
makes the spin matter, at a quarter turn and at an arbitrary yaw about z."""

from __future__ import annotations

import numpy as np
import pytest

from tests.route_fixtures import IDS, SPOTS, box_part
from weldplan.cellframe import PartPose
from weldplan.io.joints import Joints
from weldplan.tool import arc_torch, plan_weld_poses
from weldplan.tool.poses.orient import nominal_frames
from weldplan.weld.cell import build_cell

#: mm: where the part stands in the cell (off the origin, so a turn is not about the part)
AT = np.array([1500.0, -400.0, 700.0])


def _pose(yaw_deg: float) -> PartPose:
    """The part turned ``yaw_deg`` about the cell's z and moved to :data:`AT`; a quarter
    turn is written with exact zeros and ones."""
    M = np.eye(4)
    if yaw_deg == 90.0:
        M[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    else:
        c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
        M[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    M[:3, 3] = AT
    return PartPose(M, fixture_z=None, given="test")


def _poses(yaw_deg: float):
    # approached from above and tilted towards the wall, so the candidates differ per weld
    dirs = np.array([[0.3, 0.0, 1.0], [-0.3, 0.1, 1.0], [0.2, -0.2, 1.0]])
    joints = Joints(ids=IDS, xyz=SPOTS, directions=dirs / np.linalg.norm(dirs, axis=1)[:, None])
    pose = _pose(yaw_deg)
    cell = build_cell(box_part(), joints, part_pose=pose)
    return plan_weld_poses(cell, None, arc_torch(bend_angle=45.0)), pose.matrix


@pytest.mark.parametrize("yaw", [90.0, 37.0])
def test_the_part_turned_about_z_gives_the_same_poses_turned(yaw):
    still, M0 = _poses(0.0)
    turned, M1 = _poses(yaw)
    assert still.n_ok == len(IDS)  # every weld has a free pose: the comparison is of poses
    turn = M1 @ np.linalg.inv(M0)  # the cell-frame turn from one placement to the other
    for a, b in zip(still.poses, turned.poses, strict=True):
        assert (a.id, a.ok, a.spin, a.tilt, a.azimuth) == (b.id, b.ok, b.spin, b.tilt, b.azimuth)
        np.testing.assert_allclose(turn @ _matrix(a), _matrix(b), atol=1e-9)


def _matrix(p) -> np.ndarray:
    """``(4, 4)`` mm: a weld's TCP pose in the cell frame."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = p.rotation(), p.position
    return T


def test_the_nominal_frame_turns_with_the_part_and_keeps_the_axis():
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(50, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    R = _pose(37.0).matrix[:3, :3]
    F = nominal_frames(axes)
    G = nominal_frames(axes @ R.T, R)  # the same axes, turned with the part
    np.testing.assert_allclose(G, np.einsum("ij,njk->nik", R, F), atol=1e-12)
    np.testing.assert_allclose(G[:, :, 2], axes @ R.T, atol=1e-12)  # z: the approach axis
    np.testing.assert_allclose(np.linalg.det(G), 1.0, atol=1e-12)
    # without a part pose the frames are the planning frame's, as before
    np.testing.assert_array_equal(nominal_frames(axes, None), F)
