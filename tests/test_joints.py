"""Reading weld joints: the format, units, and every bad input named by file, line and column."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from weldplan.errors import InputError
from weldplan.io.joints import Joints, coincident_joints, read_joints


def write(tmp_path: Path, text: str, name: str = "joints.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_reads_ids_positions_and_no_directions(tmp_path):
    path = write(tmp_path, "id,x,y,z\n1,1443.60,-53.20,686.00\nA7,0,0.5,-1e3\n")
    j = read_joints(path)
    assert j.ids == ("1", "A7")
    np.testing.assert_array_equal(j.xyz, [[1443.60, -53.20, 686.00], [0.0, 0.5, -1000.0]])
    assert j.directions is None
    assert j.source == path
    assert len(j) == 2 and j.index("A7") == 1


def test_directions_are_normalised_and_columns_any_order(tmp_path):
    path = write(tmp_path, "Z, nz ,id,x,y,nx,ny\n3,0,j,1,2,0,-2\n")
    j = read_joints(path)
    np.testing.assert_array_equal(j.xyz, [[1, 2, 3]])
    np.testing.assert_allclose(j.directions, [[0, -1, 0]])


def test_semicolons_decimal_commas_comments_and_blank_lines(tmp_path):
    path = write(tmp_path, "# station 4\n\nid;x;y;z\n1;1443,60;-53,2;686\n\n2;1;2;3\n")
    j = read_joints(path)
    np.testing.assert_array_equal(j.xyz, [[1443.6, -53.2, 686.0], [1, 2, 3]])


def test_units_convert_positions_to_mm(tmp_path):
    path = write(tmp_path, "id,x,y,z,nx,ny,nz\n1,1.5,-0.25,2,0,0,3\n")
    j = read_joints(path, units="m")
    np.testing.assert_allclose(j.xyz, [[1500.0, -250.0, 2000.0]])
    np.testing.assert_allclose(j.directions, [[0, 0, 1]])


def test_round_trip_through_to_csv(tmp_path):
    j = Joints(
        ids=("a", "b"), xyz=[[1.1, 2.2, 3.3], [-4, 5e-3, 6]], directions=[[1, 1, 0], [0, 0, -2]]
    )
    j.to_csv(tmp_path / "out.csv")
    back = read_joints(tmp_path / "out.csv")
    assert back.ids == j.ids
    np.testing.assert_array_equal(back.xyz, j.xyz)
    np.testing.assert_allclose(back.directions, j.directions, rtol=0, atol=1e-15)


def test_joints_are_immutable():
    j = Joints(ids=("1",), xyz=[[0, 0, 0]])
    with pytest.raises(ValueError):
        j.xyz[0, 0] = 1.0


BAD = [
    # (file text, line, field, words in the message)
    ("", None, None, "empty file"),
    ("\n  \n# only a comment\n", None, None, "empty file"),
    ("id,x,y,z\n", 1, None, "no data rows"),
    ("id,x,y\n1,2,3\n", 1, "z", "missing column 'z'"),
    ("x,y,z\n1,2,3\n", 1, "id", "missing column 'id'"),
    ("id,x,y,z,nx,ny\n1,0,0,0,1,0\n", 1, "nz", "nx,ny,nz"),
    ("id,x,y,z,x\n1,0,0,0,0\n", 1, "x", "twice"),
    ("id,x,y,z\n1,0,0,0\n2,abc,0,0\n", 3, "x", "not a number"),
    ("id,x,y,z\n1,0,,0\n", 2, "y", "empty value"),
    ("id,x,y,z\n1,0,0,nan\n", 2, "z", "finite"),
    ("id,x,y,z\n1,0,0,0\n2,0,inf,0\n", 3, "y", "finite"),
    ("id,x,y,z\n1,0,0,-Infinity\n", 2, "z", "finite"),
    ("id,x,y,z\n1,0,0,0\n2,1,1,1\n1,2,2,2\n", 4, "id", "duplicate id '1'"),
    ("id,x,y,z\n,0,0,0\n", 2, "id", "empty id"),
    ("id,x,y,z,nx,ny,nz\n1,0,0,0,0,0,0\n", 2, "nx", "zero-length direction"),
    ("id,x,y,z\n1,0,0\n", 2, None, "expected 4 fields, found 3"),
    ("id,x,y,z\n1,0,0,0,5\n", 2, None, "expected 4 fields, found 5"),
    ("id,x,y,z,nx,ny,nz\n1,0,0,0,1,x,0\n", 2, "ny", "not a number"),
]


@pytest.mark.parametrize(("text", "line", "field", "words"), BAD)
def test_every_bad_input_names_file_line_and_column(tmp_path, text, line, field, words):
    path = write(tmp_path, text)
    with pytest.raises(InputError) as info:
        read_joints(path)
    err = info.value
    assert err.path == str(path)
    assert err.line == line
    assert err.field == field
    assert words in str(err)
    assert str(path) in str(err)


def test_missing_file_and_bad_units(tmp_path):
    with pytest.raises(InputError, match="not found"):
        read_joints(tmp_path / "nope.csv")
    path = write(tmp_path, "id,x,y,z\n1,0,0,0\n")
    with pytest.raises(InputError, match="unknown units"):
        read_joints(path, units="furlong")


def test_not_utf8_is_an_input_error(tmp_path):
    path = tmp_path / "bin.csv"
    path.write_bytes(b"id,x,y,z\n1,\xff\xfe,0,0\n")
    with pytest.raises(InputError, match="UTF-8"):
        read_joints(path)


def test_demo_joints_are_table_1():
    from weldplan.weld.demo_part import DEMO_JOINTS, TABLE1_XYZ

    j = read_joints(DEMO_JOINTS)
    assert j.ids == tuple(str(k) for k in range(1, 16))
    np.testing.assert_array_equal(j.xyz, TABLE1_XYZ)
    # Table 1's reference distance, joint 3 to joint 7 (DESIGN.md)
    assert np.linalg.norm(j.xyz[2] - j.xyz[6]) == pytest.approx(202.91, abs=0.005)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_joints_refuse_non_finite_positions_with_weldplans_error(bad):
    with pytest.raises(InputError, match="joint 'b'.*not finite") as info:
        Joints(ids=("a", "b"), xyz=[[0.0, 0.0, 0.0], [1.0, bad, 2.0]], lines=(2, 3))
    assert info.value.line == 3
    assert isinstance(info.value, ValueError)


def test_joints_refuse_bad_directions_absurd_positions_and_mismatched_lengths():
    with pytest.raises(InputError, match="direction"):
        Joints(ids=("a",), xyz=[[0.0, 0.0, 0.0]], directions=[[float("nan"), 0.0, 1.0]])
    with pytest.raises(InputError, match="beyond"):
        Joints(ids=("a",), xyz=[[1e300, 0.0, 0.0]])
    with pytest.raises(InputError, match="2 ids but 1 positions"):
        Joints(ids=("a", "b"), xyz=[[0.0, 0.0, 0.0]])
    with pytest.raises(InputError, match="unique"):
        Joints(ids=("a", "a"), xyz=[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])


def test_a_1e300_coordinate_in_the_csv_names_its_line_and_column(tmp_path):
    path = tmp_path / "j.csv"
    path.write_text("id,x,y,z\n1,0,0,0\n2,0,1e300,0\n")
    with pytest.raises(InputError, match="beyond") as info:
        read_joints(path)
    assert (info.value.line, info.value.field) == (3, "y")


def test_read_joints_records_lines_and_names_joints_by_them(tmp_path):
    path = tmp_path / "j.csv"
    path.write_text("# comment\nid,x,y,z\n\nA,0,0,0\nB,1,0,0\n")
    j = read_joints(path)
    assert j.lines == (4, 5)
    assert j.where(1) == f"joint 'B' ({path}, line 5)"


def test_coincident_joints_are_found_within_the_tolerance():
    j = Joints(
        ids=("a", "b", "c", "d"),
        xyz=[[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 0.0, 0.005], [100.0, 0.02, 0.0]],
    )
    assert coincident_joints(j) == [(0, 2)]
    assert coincident_joints(j, tol=0.05) == [(0, 2), (1, 3)]
