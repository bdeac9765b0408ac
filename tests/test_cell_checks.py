"""The cell's input checks (issue 14, 2.3 and item 10): settings, joints far from the part
(units and scale mistakes), joints at the same coordinates, repaired faces in the summary."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from tests.route_fixtures import box_part
from weldplan.cli import main
from weldplan.errors import InputError
from weldplan.io.joints import Joints
from weldplan.weld.cell import build_cell, default_max_joint_distance, demo_cell, load_cell

#: joints on the floor of tests/route_fixtures' box scene, in mm
JOINTS_MM = "id,x,y,z\nA,-40,0,0\nB,40,0,0\nC,-40,60,0\n"


@pytest.fixture
def files(tmp_path):
    mesh = tmp_path / "box.stl"
    box_part().export(mesh)
    joints = tmp_path / "joints.csv"
    joints.write_text(JOINTS_MM)
    return tmp_path, mesh, joints


@pytest.mark.parametrize(
    ("name", "value", "words"),
    [
        ("clearance", 0.0, "clearance must be a positive number of mm, got 0.0"),
        ("clearance", -1.0, "clearance must be a positive number of mm"),
        ("clearance", math.nan, "clearance must be a positive number of mm"),
        ("pitch", math.nan, "pitch must be a positive number of mm"),
        ("pitch", -5.0, "pitch must be a positive number of mm"),
        ("margin", -1.0, "margin must be >= 0 mm"),
        ("margin", math.inf, "margin must be >= 0 mm"),
        ("max_joint_distance", 0.0, "max_joint_distance must be a positive number of mm"),
    ],
)
def test_bad_settings_are_input_errors_with_the_clis_words(files, name, value, words):
    _, mesh, joints = files
    with pytest.raises(InputError, match=words) as info:
        load_cell(mesh, joints, **{name: value})
    assert info.value.field == name
    assert isinstance(info.value, ValueError)


def test_a_joint_10_m_from_the_part_is_named_with_its_line_and_distance(files):
    tmp, mesh, _ = files
    joints = tmp / "far.csv"
    joints.write_text(JOINTS_MM + "D,10000,0,0\n")
    with pytest.raises(InputError, match=r"joint 'D'.*9900\.0 mm from the part") as info:
        load_cell(mesh, joints)
    assert info.value.line == 5
    assert info.value.path == str(joints)
    assert "--units" in str(info.value) and "--scale" in str(info.value)


def test_joints_in_metres_beside_a_mesh_in_mm_are_refused(tmp_path):
    """The demo's joints written in metres: read as mm they sit 1.4 m from the part."""
    from weldplan.io.joints import read_joints
    from weldplan.weld.demo_part import DEMO_JOINTS, DEMO_PART

    j = read_joints(DEMO_JOINTS)
    metres = tmp_path / "metres.csv"
    Joints(ids=j.ids, xyz=j.xyz / 1000.0).to_csv(metres)
    with pytest.raises(InputError, match=r"joint '\d+'.* mm from the part's surface") as info:
        load_cell(DEMO_PART, metres)
    assert info.value.path == str(metres) and info.value.line is not None
    assert "units" in str(info.value)


def test_a_wrong_scale_is_refused_and_the_limit_can_be_raised(files):
    _, mesh, joints = files
    with pytest.raises(InputError, match=r"joint 'C'.*44\.7 mm from the part"):
        load_cell(mesh, joints, scale=0.2)  # the floor shrinks to 40 mm: C is 44.7 mm off
    cell = load_cell(mesh, joints, scale=0.2, max_joint_distance=100.0)
    assert cell.summary()["checks"]["max_joint_distance_mm"] == 100.0


def test_default_limit_follows_clearance_and_pitch():
    assert default_max_joint_distance(5.0, 5.0) == 40.0
    assert default_max_joint_distance(1.0, 1.0) == 20.0
    assert default_max_joint_distance(10.0, 5.0) == 60.0
    assert default_max_joint_distance(5.0, 5.0, search_radius=80.0) == 80.0


def test_joints_at_the_same_coordinates_are_warned_and_counted(files, caplog):
    tmp, mesh, _ = files
    joints = tmp / "twice.csv"
    joints.write_text(JOINTS_MM + "D,-40,0,0.001\n")
    with caplog.at_level("WARNING", logger="weldplan.weld.cell"):
        cell = load_cell(mesh, joints)
    assert "joint 'A'" in caplog.text and "joint 'D'" in caplog.text
    assert "line 5" in caplog.text
    assert cell.summary()["checks"]["coincident_joints"] == [["A", "D"]]
    assert "1 pairs of joints at the same coordinates: A=D" in cell.format_summary()


def test_removed_faces_reach_the_cell_summary(tmp_path):
    part = box_part()
    faces = np.vstack([part.faces, part.faces[:1], [[0, 0, 1]]])  # a duplicate, a degenerate
    path = tmp_path / "dirty.obj"
    path.write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in part.vertices)
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)
    )
    joints = tmp_path / "j.csv"
    joints.write_text(JOINTS_MM)
    cell = load_cell(path, joints)
    assert cell.summary()["checks"]["faces_removed"] == {
        "degenerate_faces": 1,
        "duplicate_faces": 1,
    }
    assert "removed 1 degenerate and 1 duplicate faces" in cell.format_summary()
    assert cell.provenance["mesh"]["repairs"] == {"degenerate_faces": 1, "duplicate_faces": 1}


def test_build_cell_refuses_what_is_not_a_part_or_joints():
    j = Joints(ids=("A",), xyz=[[0.0, 0.0, 0.0]])
    with pytest.raises(InputError, match="trimesh"):
        build_cell(trimesh.Trimesh(), j)
    with pytest.raises(InputError, match="Joints"):
        build_cell(box_part(), [[0.0, 0.0, 0.0]])  # type: ignore[arg-type]


def test_cli_plan_names_the_far_joint_and_takes_max_joint_distance(files, capsys):
    tmp, mesh, _ = files
    joints = tmp / "far.csv"
    joints.write_text(JOINTS_MM + "D,-40,0,30\n")  # 30 mm above the floor: beyond 20 mm
    argv = ["plan", str(mesh), str(joints), "-o", str(tmp / "r.csv"), "--quiet", "--pitch", "2"]
    argv += ["--clearance", "2"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "joint 'D'" in err and "30.0 mm" in err
    with pytest.raises(SystemExit) as e:
        main([*argv, "--max-joint-distance", "nan"])
    assert e.value.code == 2


def test_a_settings_object_and_its_keywords_build_the_same_cell():
    from weldplan.weld.cellsettings import CellBuildSettings

    cell = demo_cell(settings=CellBuildSettings(pitch=10.0, margin=40.0))
    same = demo_cell(pitch=10.0, margin=40.0)
    over = demo_cell(settings=CellBuildSettings(pitch=5.0), pitch=10.0, margin=40.0)
    for c in (same, over):
        assert c.grid.shape == cell.grid.shape and c.pitch == cell.pitch == 10.0
        assert np.array_equal(c.virtual_index, cell.virtual_index)
    # the default joint distance follows the pitch it is laid over
    limit = CellBuildSettings(pitch=10.0).joint_distance_limit
    assert limit == default_max_joint_distance(5.0, 10.0)
    with pytest.raises(InputError) as info:
        CellBuildSettings(margin=-1.0)
    assert info.value.field == "margin"
    with pytest.raises(TypeError, match="'pich'"):
        demo_cell(pich=10.0)
