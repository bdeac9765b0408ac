"""The weld feasibility study (weldplan.study, issue 29 item 4) on the demo cell with the shared
spot gun and the KUKA KR 150: its verdicts against independent checks (python-fcl of the gun at
the reported pose, FK and link collisions of the reported configuration), a spot off the part,
a robot out of reach, the reach matrix and the JSON round trip."""

from __future__ import annotations

from pathlib import Path

import fcl
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.conftest import require_shared
from weldplan.errors import ConfigError
from weldplan.io.joints import Joints, read_joints
from weldplan.io.mesh import load_part
from weldplan.study.result import (
    NO_SURFACE,
    NOT_ANALYSED,
    OK,
    OUT_OF_REACH,
    FeasibilityStudy,
)

ROOT = Path(__file__).resolve().parents[1]
#: demo spots of the study: 15 needs A2 past its limit from BASE (every free gun pose)
IDS = ("1", "7", "9", "13", "15")
#: the robot 1 m behind the demo part on its lowest plane, facing it (the study's searched base)
BASE = (448.1, 95.3, 652.7, -7.5)
#: a spot moved this far off the part along its approach direction
OFF_MM = 30.0


def _spots() -> Joints:
    j = read_joints(ROOT / "assets" / "demo" / "joints.csv")
    k = [j.ids.index(i) for i in IDS]
    xyz = np.asarray(j.xyz)[k]
    d = np.asarray(j.directions)[k]
    off = xyz[0] + OFF_MM * d[0]  # the direction points from the joint towards the gun
    return Joints(ids=(*IDS, "off"), xyz=np.vstack([xyz, off]), directions=np.vstack([d, d[0]]))


def _gun():
    from weldplan.study import load_study_tool

    path = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    return load_study_tool(str(path), tcp="nozzle_tip", name="gun")


def _robot(base):
    from weldplan.robot import load_robot
    from weldplan.robot.placement import base_pose

    urdf = require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    return load_robot(urdf, base=base_pose(*base))


@pytest.fixture(scope="module")
def cell():
    return load_part(ROOT / "assets" / "demo" / "part.stl"), _spots(), _gun()


@pytest.fixture(scope="module")
def study(cell):
    from weldplan.study import StudyRobot, check_spots

    part, spots, gun = cell
    robots = [
        StudyRobot("near", _robot(BASE)),
        StudyRobot("far", _robot((20000.0, 0.0, 652.7, 180.0))),
    ]
    return check_spots(part, spots, [gun], robots)


def _tcp(position, quaternion) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat(np.roll(quaternion, -1)).as_matrix()
    T[:3, 3] = position
    return T


def _bvh(v, f) -> fcl.CollisionObject:
    m = fcl.BVHModel()
    m.beginModel(len(v), len(f))
    m.addSubModel(np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64))
    m.endModel()
    return fcl.CollisionObject(m, fcl.Transform())


def _distance(a: fcl.CollisionObject, T: np.ndarray, b: fcl.CollisionObject) -> float:
    a.setTransform(fcl.Transform(T[:3, :3], T[:3, 3]))
    return fcl.distance(a, b, fcl.DistanceRequest(), fcl.DistanceResult())


def test_the_gun_at_every_reported_pose_is_clear_of_the_part_outside_its_contact_zone(cell, study):
    """python-fcl on the raw meshes: the gun's triangles wholly outside the contact sphere stay
    at least the clearance from the part (no shared code with the pose search's zone cut)."""
    part, _, gun = cell
    s = study.settings
    V, F = gun.tool.vertices, gun.tool.faces
    outside = np.linalg.norm(V[F], axis=2).min(axis=1) > s["contact_radius"]
    tool = _bvh(V, F[outside])
    body = _bvh(part.vertices, part.faces)
    poses = [(sp.position, sp.guns[0].quaternion) for sp in study.spots if sp.guns[0].ok]
    poses += [(sp.position, r.quaternion) for sp in study.spots for r in sp.robots if r.ok]
    assert len(poses) >= 5
    for p, q in poses:
        assert _distance(tool, _tcp(p, q), body) >= s["clearance"] - 1e-6


def test_the_reported_configuration_reaches_the_pose_within_limits_with_its_links_clear(
    cell, study
):
    """FK of the reported q equals the TCP pose; q inside the limits, A5 off 0; each link's
    mesh (python-fcl at the FK frames) does not touch the part."""
    from weldplan.robot.model import chain_transform

    part, _, _ = cell
    robot = _robot(BASE)
    gun_urdf = require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    F = robot.tool_transform(chain_transform(gun_urdf, "nozzle_tip"))
    body = _bvh(part.vertices, part.faces)
    links = [(lk.index, _bvh(lk.vertices, lk.faces)) for lk in robot.links]
    served = [(sp, sp.robots[0]) for sp in study.spots if sp.robots[0].ok]
    assert len(served) == 4  # every spot but 15 and the one off the part
    for sp, v in served:
        q = np.array(v.q)
        T = robot.fk(q)[0] @ F
        assert np.allclose(T, _tcp(sp.position, v.quaternion), atol=1e-6)
        assert robot.in_limits(q)[0] and abs(np.sin(q[4])) >= np.sin(np.radians(5.0))
        frames = robot.link_frames(q)[0]
        for i, obj in links:
            obj.setTransform(fcl.Transform(frames[i][:3, :3], frames[i][:3, 3]))
            assert not fcl.collide(obj, body, fcl.CollisionRequest(), fcl.CollisionResult())


def test_a_spot_that_needs_a_joint_past_its_limit_says_which(study):
    v = study.robot_verdict("15", "gun", "near")
    assert v.status == "joint_limit" and "A2" in v.reason and "limits" in v.reason
    assert v.q is None and v.poses_tried > 1
    assert study.spots[study.ids.index("15")].guns[0].ok  # the gun closes there


def test_a_spot_off_the_part_is_no_surface_for_every_tool_and_robot(study):
    sp = study.spots[study.ids.index("off")]
    assert sp.surface_distance == pytest.approx(OFF_MM, abs=0.5)
    assert [g.status for g in sp.guns] == [NO_SURFACE]
    assert [r.status for r in sp.robots] == [NO_SURFACE, NO_SURFACE]
    assert "no surface within 5 mm" in sp.guns[0].reason and not sp.feasible
    assert sp.stack == "none (no surface)"


def test_a_robot_far_away_reaches_nothing(study):
    far = [sp.robots[1] for sp in study.spots if sp.guns[0].ok]
    assert len(far) == len(IDS) and all(v.status == OUT_OF_REACH for v in far)


def test_the_reach_matrix_is_the_verdicts(study):
    R = study.reach_matrix()
    assert R.shape == (len(IDS) + 1, 2)
    expect = [[sp.robots[0].ok, sp.robots[1].ok] for sp in study.spots]
    assert R.tolist() == expect
    assert study.reach_matrix("gun").tolist() == expect
    assert R[:, 0].sum() == 4 and not R[:, 1].any()
    assert study.gun_matrix()[:, 0].tolist() == [True] * len(IDS) + [False]
    assert study.feasible.tolist() == R.any(axis=1).tolist()
    with pytest.raises(KeyError, match="no tool named 'torch'"):
        study.reach_matrix("torch")


def test_the_spots_no_robot_reaches_are_listed_with_why(study):
    un = study.unreached()
    assert list(un) == ["15", "off"]
    assert un["15"].startswith("gun/near: joint_limit A2") and "gun/far: out_of_reach" in un["15"]
    assert "no_surface no surface within 5 mm" in un["off"]


def test_the_study_round_trips_through_json(study):
    back = FeasibilityStudy.from_json(study.to_json())
    assert back == study
    assert back.robots[0].xyz_yaw() == pytest.approx(BASE, abs=1e-9)
    assert back.frame == "part" and back.spots[0].stack == NOT_ANALYSED


def test_the_gun_counts_its_free_candidates(study):
    for sp in study.spots[: len(IDS)]:
        g = sp.guns[0]
        assert g.status == OK and 0 < g.n_free <= g.n_candidates
        assert g.n_candidates == study.spots[0].guns[0].n_candidates


def test_the_stack_hook_fills_the_column(cell):
    """The hook's words go in the column of the spots on the part; a spot off it says so."""
    from weldplan.study import check_spots

    part, spots, gun = cell
    two = Joints(ids=("1", "off"), xyz=np.asarray(spots.xyz)[[0, -1]], directions=None)
    study = check_spots(part, two, [gun], stacks=lambda p, xyz: ["2 sheets"] * len(xyz))
    assert [s.stack for s in study.spots] == ["2 sheets", "none (no surface)"]
    with pytest.raises(ConfigError, match="stack hook gave 0 words"):
        check_spots(part, two, [gun], stacks=lambda p, xyz: [])


@pytest.mark.parametrize(
    ("field", "value"),
    [("clearance", -1.0), ("max_spot_distance", float("nan")), ("robot_poses", 0),
     ("cone", 95.0), ("floor_z", float("inf"))],
)  # fmt: skip
def test_bad_settings_are_refused_by_name(field, value):
    from weldplan.study import StudySettings

    with pytest.raises(ConfigError) as exc:
        StudySettings(**{field: value})
    assert exc.value.field == field


def test_a_study_without_a_tool_or_with_two_tools_of_one_name_is_refused(cell):
    from weldplan.study import check_spots

    part, spots, gun = cell
    with pytest.raises(ConfigError, match="at least one tool"):
        check_spots(part, spots, [])
    with pytest.raises(ConfigError, match="share a name"):
        check_spots(part, spots, [gun, gun])


def test_a_base_with_nothing_to_search_on_says_so(cell):
    """Every spot off the part: a searched robot keeps its own base, and the result says why."""
    from weldplan.study import StudyRobot, check_spots

    part, spots, gun = cell
    one = Joints(ids=("off",), xyz=np.asarray(spots.xyz)[-1:], directions=None)
    study = check_spots(part, one, [gun], [StudyRobot("r", _robot(BASE), searched=True)])
    info = study.robots[0]
    assert not info.searched and "no spot has a free gun pose" in info.note
    assert study.spots[0].robots[0].status == NO_SURFACE
    assert FeasibilityStudy.from_json(study.to_json()) == study


def test_a_mesh_tool_is_mounted_as_the_robot_stage_mounts_it(tmp_path):
    """load_study_tool mounts a mesh tool as the robot stage does (station/mount.flange_tcp):
    the robot's flange mount, then the TCP x,y,z in the tool's units and fixed-axis x-y-z
    degrees (built here with scipy, apart from the mounting code)."""
    from scipy.spatial.transform import Rotation

    from weldplan.study import load_study_tool
    from weldplan.tool import arc_torch

    arc_torch(bend_angle=0.0).mesh.export(tmp_path / "torch.stl")
    st = load_study_tool(str(tmp_path / "torch.stl"), tcp="1,-2,3,10,-20,30", units="mm")
    robot = _robot(BASE)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", [10.0, -20.0, 30.0], degrees=True).as_matrix()
    T[:3, 3] = [1.0, -2.0, 3.0]
    assert np.allclose(st.flange_tcp(robot), robot.mount @ T, atol=1e-9)
    assert st.name == "torch" and st.spec.tcp == "1,-2,3,10,-20,30"


def test_no_spots_is_an_empty_study(cell):
    from weldplan.study import StudyRobot, check_spots

    part, _, gun = cell
    none = Joints(ids=(), xyz=np.zeros((0, 3)))
    study = check_spots(part, none, [gun], [StudyRobot("near", _robot(BASE))])
    assert study.spots == () and study.reach_matrix().shape == (0, 1) and study.all_feasible
