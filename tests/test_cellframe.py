"""The cell frame (weldplan.cellframe): the part placed in the cell, at load, in the base search,
in the programs' work object and at the CLI.

Answers are independent of the code under test: the README's rule for car2 ((x, y, z) ->
(x, -z, y)), rotation matrices composed by hand, KUKA's A, B, C read back by the KRL post's own
Euler function, and FK of the URDF chain through the parsed programs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.cli_helpers import one_line_error, run_cli
from tests.conftest import ROOT, require_shared
from tests.output_check import comments
from weldplan.cellframe import UP_AXES, PartPose, parse_part_pose, place_part, recorded_pose
from weldplan.errors import InputError
from weldplan.io.joints import Joints

DEMO_PART = ROOT / "assets" / "demo" / "part.stl"
DEMO_JOINTS = ROOT / "assets" / "demo" / "joints.csv"
CAR2_50 = ROOT / "assets" / "car2" / "car2_synthetic_50.csv"


def _rx(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


# ---------------------------------------------------------------------------- the pose itself
@pytest.mark.parametrize("axis", UP_AXES)
def test_each_up_axis_turns_to_the_cells_z_by_a_proper_rotation(axis):
    R = PartPose.from_up(axis).rotation
    v = np.zeros(3)
    v["xyz".index(axis[-1])] = -1.0 if axis.startswith("-") else 1.0
    np.testing.assert_array_equal(R @ v, [0.0, 0.0, 1.0])
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-15)


def test_up_y_is_the_data_readmes_rule():
    p = np.array([[1.0, 2.0, 3.0], [-4.0, 5.5, -6.0]])
    got = PartPose.from_up("y", fixture_z=None).to_cell(p)
    np.testing.assert_array_equal(got, np.c_[p[:, 0], -p[:, 2], p[:, 1]])
    assert PartPose.from_up("+Y").given == "up y"


def test_xyzrpy_is_fixed_axes_x_then_y_then_z_and_kukas_abc():
    from weldplan.io.posts.krl import abc_deg

    pose = PartPose.from_xyzrpy([100, -200, 300, 10, -25, 140])
    np.testing.assert_allclose(pose.rotation, _rz(140) @ _ry(-25) @ _rx(10), atol=1e-12)
    np.testing.assert_array_equal(pose.matrix[:3, 3], [100, -200, 300])
    np.testing.assert_allclose(abc_deg(pose.rotation), [140, -25, 10], atol=1e-9)  # A, B, C


def test_round_trip_of_the_welds_part_cell_part():
    rng = np.random.default_rng(7)
    xyz = rng.uniform(-2000, 2000, (40, 3))
    d = rng.normal(size=(40, 3))
    joints = Joints(ids=tuple(f"J{k}" for k in range(40)), xyz=xyz, directions=d, lines=range(40))
    pose = PartPose.from_xyzrpy(np.r_[rng.uniform(-1e3, 1e3, 3), rng.uniform(-180, 180, 3)])
    cell = pose.joints_to_cell(joints)
    # positions move rigidly: the distances between welds stay; directions turn, unit length
    iu = np.triu_indices(40, 1)
    dist = np.linalg.norm(xyz[:, None] - xyz[None], axis=2)[iu]
    dist_cell = np.linalg.norm(cell.xyz[:, None] - cell.xyz[None], axis=2)[iu]
    np.testing.assert_allclose(dist_cell, dist, rtol=1e-12)
    np.testing.assert_allclose(cell.directions, joints.directions @ pose.rotation.T, atol=1e-15)
    back = pose.joints_to_part(cell)
    np.testing.assert_allclose(back.xyz, joints.xyz, atol=1e-9)
    np.testing.assert_allclose(back.directions, joints.directions, atol=1e-12)
    assert back.ids == joints.ids and back.lines == joints.lines


def test_the_fixture_height_puts_the_lowest_point_there():
    pts = np.array([[0.0, -50.0, 0.0], [10.0, 400.0, 20.0], [5.0, 30.0, -90.0]])
    for fixture, floor in ((0.0, 0.0), (250.0, 0.0), (250.0, -100.0)):
        placed = PartPose.from_up("y", fixture_z=fixture, floor_z=floor).placed(pts)
        assert placed.to_cell(pts)[:, 2].min() == pytest.approx(floor + fixture, abs=1e-12)
    explicit = PartPose.from_xyzrpy([0, 0, 77, 0, 0, 0])  # no fixture height: the z stands
    assert explicit.placed(pts) is explicit


def test_the_route_json_record_reads_back_exactly():
    pose = PartPose.from_xyzrpy([1.5, 2, 3, 10, 20, 30], fixture_z=12.0, floor_z=-3.0)
    back = PartPose.from_dict(pose.to_dict())
    np.testing.assert_array_equal(back.matrix, pose.matrix)
    assert (back.floor_z, back.fixture_z, back.given) == (-3.0, 12.0, pose.given)


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: PartPose.from_up("w"), "up"),
        (lambda: PartPose.from_xyzrpy([np.nan, 0, 0, 0, 0, 0]), "part_pose"),
        (lambda: PartPose.from_xyzrpy([0, 0, 0, 0, np.inf, 0]), "part_pose"),
        (lambda: PartPose.from_xyzrpy([0, 0, 0, 0, 0]), "part_pose"),
        (lambda: PartPose(np.diag([1.0, 1.0, -1.0, 1.0])), "part_pose"),  # a mirror
        (lambda: PartPose(np.diag([2.0, 2.0, 2.0, 1.0])), "part_pose"),  # a scale
        (lambda: PartPose(np.eye(3)), "part_pose"),
        (lambda: PartPose(np.r_[np.eye(4)[:3], [[0, 0, 1, 1]]]), "part_pose"),
        (lambda: PartPose(np.eye(4), floor_z=math.nan), "floor_z"),
        (lambda: PartPose.from_dict({"matrix": [[1, 0], [0, 1]]}), "part_pose.matrix"),
    ],
)
def test_bad_poses_are_one_line_input_errors_naming_the_field(make, field):
    with pytest.raises(InputError) as e:
        make()
    assert e.value.field == field
    assert "\n" not in str(e.value)


def test_a_matrix_file_reads_and_its_errors_name_file_and_line(tmp_path):
    good = PartPose.from_xyzrpy([10, 20, 30, 0, 90, 45])
    f = tmp_path / "pose.txt"
    f.write_text(
        "# part -> cell\n" + "\n".join(" ".join(repr(float(v)) for v in r) for r in good.matrix)
    )
    np.testing.assert_array_equal(parse_part_pose(str(f)).matrix, good.matrix)
    np.testing.assert_allclose(parse_part_pose("10,20,30,0,90,45").matrix, good.matrix)
    f.write_text("1 0 0 0\n0 1 0 0\n0 0 1 nan\n0 0 0 1\n")
    with pytest.raises(InputError) as e:
        parse_part_pose(str(f))
    assert (e.value.path, e.value.line) == (str(f), 3)
    f.write_text("1 0 0 0\n0 0 1 0\n0 0 1 0\n0 0 0 1\n")  # two equal rows: not a rotation
    with pytest.raises(InputError, match="not a rotation"):
        parse_part_pose(str(f))
    with pytest.raises(InputError, match="neither six numbers"):
        parse_part_pose(str(tmp_path / "missing.txt"))


def test_verify_re_applies_the_recorded_pose_and_refuses_another(tmp_path):
    import trimesh

    part = trimesh.creation.box(extents=(100.0, 60.0, 40.0))
    planned = PartPose.from_up("y", fixture_z=100.0).placed(part.vertices)
    prov = {"frame": "cell", "part_pose": planned.to_dict()}
    assert recorded_pose(prov, None, part).same_as(planned)
    assert recorded_pose(prov, PartPose.from_up("y", fixture_z=100.0), part).same_as(planned)
    with pytest.raises(InputError, match="planned with part pose up y"):
        recorded_pose(prov, PartPose.from_up("y", fixture_z=0.0), part)
    with pytest.raises(InputError, match="planned in the part frame"):
        recorded_pose({"frame": "part", "part_pose": None}, planned, part)
    assert recorded_pose({}, None, part) is None


# ---------------------------------------------------------------------------- car2 upright
@pytest.fixture(scope="module")
def car2():
    from weldplan.io.mesh import load_part

    return load_part(require_shared("bodies", "car2.obj"), length=4500.0)


@pytest.mark.parametrize("fixture", [0.0, 350.0])
def test_car2_up_y_stands_with_its_height_along_z_at_the_fixture_height(car2, fixture):
    cell_part, _, pose = place_part(car2, None, PartPose.from_up("y", fixture_z=fixture))
    v, w = np.asarray(car2.vertices), np.asarray(cell_part.vertices)
    np.testing.assert_allclose(w[:, :2], np.c_[v[:, 0], -v[:, 2]], atol=1e-9)
    assert w[:, 2].min() == pytest.approx(fixture, abs=1e-9)
    # its height (the file's y) is now the cell's z, its length still x, its width y
    np.testing.assert_allclose(cell_part.extents, car2.extents[[0, 2, 1]], rtol=1e-12)
    assert cell_part.extents[2] < cell_part.extents[1] < cell_part.extents[0]
    assert pose.matrix[2, 3] == pytest.approx(fixture - v[:, 1].min(), abs=1e-9)


def test_load_cell_with_a_pose_plans_in_the_cell_frame(car2):
    from weldplan.io.joints import read_joints
    from weldplan.weld.cell import load_cell

    car2_obj = require_shared("bodies", "car2.obj")
    pose = PartPose.from_up("y")
    cell = load_cell(car2_obj, CAR2_50, length=4500.0, part_pose=pose, margin=20.0)
    given = read_joints(CAR2_50)
    xyz = given.xyz
    lift = -np.asarray(car2.vertices)[:, 1].min()
    np.testing.assert_allclose(
        cell.joints.xyz, np.c_[xyz[:, 0], -xyz[:, 2], xyz[:, 1] + lift], atol=1e-9
    )
    d = given.directions
    np.testing.assert_allclose(cell.joints.directions, np.c_[d[:, 0], -d[:, 2], d[:, 1]])
    assert cell.part.bounds[0, 2] == pytest.approx(0.0, abs=1e-9)
    assert cell.frame == "cell"
    rec = cell.provenance
    assert rec["frame"] == "cell"
    np.testing.assert_array_equal(
        PartPose.from_dict(rec["part_pose"]).matrix, cell.part_pose.matrix
    )
    # the joints still sit on the part (the distance check ran in the cell frame)
    assert cell.diagnostics["joint_distance_max_mm"] < 1.0


def test_the_base_search_stands_the_robot_on_the_cell_floor(car2):
    from tests.robot_fixtures import shared_robot
    from weldplan.geometry.distance import SurfaceDistance
    from weldplan.io.joints import read_joints
    from weldplan.robot.collision import cell_floor
    from weldplan.robot.placement import BaseSearch, candidate_bases, search_base

    robot = shared_robot()
    cell_part, joints, _ = place_part(car2, read_joints(CAR2_50), PartPose.from_up("y"))
    pick = np.arange(0, len(joints), 5)
    T = np.repeat(np.eye(4)[None], len(pick), axis=0)  # flange z against the approach
    for k, j in enumerate(pick):
        z = -joints.directions[j]
        x = np.cross([0.0, 0.0, 1.0], z) if abs(z[2]) < 0.9 else np.array([1.0, 0, 0])
        x /= np.linalg.norm(x)
        T[k, :3, :3] = np.c_[x, np.cross(z, x), z]
        T[k, :3, 3] = joints.xyz[j] + 500.0 * joints.directions[j]
    search = BaseSearch(floor_z=0.0, heights=(0.0, 400.0), step=500.0, extra_yaws=())
    bases = candidate_bases(robot, T, cell_part, search)
    assert len(bases) > 0
    assert set(np.round(bases[:, 2, 3], 9)) <= {0.0, 400.0}
    np.testing.assert_allclose(bases[:, :3, 2], np.tile([0.0, 0.0, 1.0], (len(bases), 1)))
    top = search_base(robot, T, cell_part, search, top=3)
    assert top and all(p.base[2, 3] in (0.0, 400.0) for p in top)
    # the bases stand off the body (the search dropped columns through it)
    d = SurfaceDistance(cell_part)(np.array([p.base[:3, 3] + [0, 0, 1.0] for p in top]))
    assert np.all(d > 0)
    assert cell_floor(search, None) == 0.0  # a known floor: checked against the links


# ---------------------------------------------------------------------------- the programs
@pytest.fixture(scope="module")
def program_build():
    from tests.robot_fixtures import box_joint_route, gun_tcp, shared_robot
    from tests.route_fixtures import box_part
    from weldplan.robot.model import urdf_payload
    from weldplan.robot.program import robot_program
    from weldplan.robot.settings import ProgramSettings, ToolOnRobot

    robot = shared_robot()
    Tft, gun = gun_tcp(robot)
    route, Q = box_joint_route(robot, Tft)
    mass, cog = urdf_payload(gun)
    b = robot_program(
        route, Q, robot, ToolOnRobot(Tft, mass=mass, cog=(robot.mount @ np.r_[cog, 1.0])[:3]),
        part=box_part(), settings=ProgramSettings(weld_time=0.5),
    )  # fmt: skip
    return robot, route, Q, b


def _part_frame_welds(route, pose):
    """``{joint id: (3,)}``: the route's welds (planning = cell frame) in the part frame."""
    return {jid: pose.to_part(route.joint_xyz[k])[0] for k, jid in enumerate(route.joint_ids)}


@pytest.mark.parametrize("post", ["rapid", "krl"])
def test_fk_through_the_work_object_lands_on_the_part_frame_welds(program_build, post):
    import dataclasses

    from weldplan.io.posts.krl import render_krl
    from weldplan.io.posts.parse import parse_krl, parse_rapid
    from weldplan.io.posts.rapid import render_rapid

    robot, route, Q, b = program_build
    # the box route's frame is the cell; the part stands in it turned and lifted
    pose = PartPose.from_xyzrpy([350.0, -120.0, 80.0, 5.0, -10.0, 30.0])
    prog = dataclasses.replace(b.program, part_pose=pose.matrix)
    if post == "rapid":
        text = render_rapid(prog)
        mod = parse_rapid(text)
        np.testing.assert_allclose(mod.oframe, pose.matrix, atol=1e-3)
        np.testing.assert_allclose(mod.uframe, np.linalg.inv(robot.base), atol=1e-3)
        wobj, tool = mod.wobj, mod.tool
        targets = {name: mod.targets[name][0] for _, name, _, _ in mod.moves}
    else:
        src, dat = render_krl(prog)
        text = src + dat
        kp = parse_krl(src, dat)
        wobj, tool = kp.base, kp.tool
        targets = {name: kp.points[name][0] for _, name, _, _ in kp.moves}
    assert "the targets are in the part frame" in text
    welds = _part_frame_welds(route, pose)
    n = 0
    for t, T_prog in zip(prog.targets, targets.values(), strict=True):
        fk_base = np.linalg.solve(robot.base, robot.fk(Q[t.row])[0])  # flange, robot base
        tcp_part = np.linalg.solve(wobj, fk_base @ tool)  # TCP through the work object
        np.testing.assert_allclose(tcp_part[:3, 3], T_prog[:3, 3], atol=0.01)
        if t.kind == "weld":
            np.testing.assert_allclose(tcp_part[:3, 3], welds[t.joint_id], atol=0.01)
            n += 1
    assert n == len(route.joint_ids)


def test_without_a_part_pose_the_work_object_is_unchanged(program_build):
    from weldplan.io.posts.rapid import render_rapid

    text = render_rapid(program_build[3].program)
    assert "[[0,0,0],[1,0,0,0]]];" in text and "part frame (the coordinates" not in text


# ---------------------------------------------------------------------------- the CLI
@pytest.mark.parametrize(
    "opts, words",
    [
        (["--up", "w"], "--up"),
        (["--part-pose", "nan,0,0,0,0,0"], "--part-pose"),
        (["--part-pose", "1,2,3"], "--part-pose"),
        (["--up", "y", "--fixture-z", "inf"], "--fixture-z"),
        (["--fixture-z", "10"], "--fixture-z"),
        (["--up", "y", "--part-pose", "0,0,0,0,0,0"], "not both"),
    ],
)
def test_cli_bad_poses_exit_2_with_one_line(tmp_path, capsys, opts, words):
    out = tmp_path / "r.csv"
    code = run_cli(["plan", str(DEMO_PART), str(DEMO_JOINTS), "-o", str(out), *opts])
    assert code == 2
    assert words in one_line_error(capsys)
    assert not out.exists()


def test_cli_a_non_rotation_matrix_file_exits_2_naming_it(tmp_path, capsys):
    f = tmp_path / "pose.txt"
    f.write_text("1 0 0 0\n0 1 0 0\n0 0 -1 0\n0 0 0 1\n")
    out = tmp_path / "r.csv"
    code = run_cli(
        ["plan", str(DEMO_PART), str(DEMO_JOINTS), "-o", str(out), "--part-pose", str(f)]
    )
    assert code == 2
    line = one_line_error(capsys)
    assert str(f) in line and "not a rotation" in line


@pytest.mark.slow
def test_cli_plan_in_the_cell_and_verify_re_applies_the_pose(tmp_path, capsys):
    import json

    from weldplan.io.joints import read_joints

    csv, js = tmp_path / "r.csv", tmp_path / "r.json"
    pose_opt = ["--part-pose", "1000,-500,300,10,-20,35"]
    argv = ["plan", str(DEMO_PART), str(DEMO_JOINTS), "-o", str(csv), "--json", str(js)]
    assert run_cli([*argv, *pose_opt, "--quiet"]) == 0
    rec = json.loads(js.read_text())["provenance"]
    assert rec["frame"] == "cell"
    pose = PartPose.from_dict(rec["part_pose"])
    assert [c for c in comments(csv.read_text()) if c.startswith("frame: cell")]
    # the CSV's weld rows are the joints moved by the pose
    joints = read_joints(DEMO_JOINTS)
    lines = [ln for ln in csv.read_text().splitlines() if not ln.startswith("#")]
    rows = [r.split(",") for r in lines[1:]]
    welds = {r[2]: np.array([float(v) for v in r[3:6]]) for r in rows if r[1] == "weld"}
    for k, jid in enumerate(joints.ids):
        np.testing.assert_allclose(welds[jid], pose.to_cell(joints.xyz[k])[0], atol=1e-3)
    capsys.readouterr()
    ver = ["verify", str(js), str(DEMO_PART), "--joints", str(DEMO_JOINTS)]
    assert run_cli(ver) == 0  # the pose re-applied from the route
    assert run_cli([*ver, *pose_opt]) == 0
    capsys.readouterr()
    assert run_cli([*ver, "--part-pose", "1000,-500,300,10,-20,36"]) == 2
    assert "planned with part pose" in one_line_error(capsys)


@pytest.mark.slow
def test_cli_the_floor_sets_where_the_fixture_stands_without_a_robot(tmp_path):
    import json

    from weldplan.io.mesh import load_part

    js = tmp_path / "r.json"
    argv = ["plan", str(DEMO_PART), str(DEMO_JOINTS), "-o", str(tmp_path / "r.csv")]
    opts = ["--json", str(js), "--up", "z", "--floor-z", "-200", "--fixture-z", "50", "--quiet"]
    assert run_cli([*argv, *opts]) == 0
    pose = PartPose.from_dict(json.loads(js.read_text())["provenance"]["part_pose"])
    assert (pose.floor_z, pose.fixture_z) == (-200.0, 50.0)
    low = pose.to_cell(load_part(DEMO_PART).vertices)[:, 2].min()
    assert low == pytest.approx(-150.0, abs=1e-9)
