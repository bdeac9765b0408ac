"""Fault injection at the command line (issue #14, section 2): hostile inputs, one invariant.

Every case ends in a one-line error (exit 2 bad input, 1 failure, 3 skipped; no traceback; the
line names the file, field, joint or option) or in a route that the independent oracle of
tests/faults/oracle.py confirms. Cases whose fix lands on another branch are strict xfails that
name the item and the branch, so they flip when the branches merge.
"""

from __future__ import annotations

import errno
import json
import os

import numpy as np
import pytest
import trimesh

from tests.faults.harness import (
    BAD_INPUT,
    FAILURE,
    SPOTS,
    UP,
    Scene,
    assert_invariant,
    assert_one_line_error,
    closed_box,
    make_scene,
    plate,
    run_cli,
    sheet,
    wall_plate,
    write_joints,
)
from tests.faults.oracle import check_route_file


def _xfail(item: int, branch: str, what: str = ""):
    return pytest.mark.xfail(
        strict=True,
        reason=f"#14 item {item}: fixed on branch {branch}" + (f" ({what})" if what else ""),
    )


GEOM = "geom-trust"
CLI = "cli-trust"


def _obj_scene(tmp_path, bad_vertex) -> Scene:
    """The wall plate as an OBJ whose highest wall vertex is replaced by ``bad_vertex``: with the
    wall's faces dropped, a route straight through the wall would look free."""
    m = wall_plate()
    v = np.asarray(m.vertices, dtype=float).copy()
    v[int(np.argmax(v[:, 2]))] = bad_vertex
    lines = [f"v {float(a)!r} {float(b)!r} {float(c)!r}" for a, b, c in v]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(m.faces)]
    (tmp_path / "part.obj").write_text("\n".join(lines) + "\n")
    write_joints(tmp_path / "joints.csv", SPOTS, np.tile(UP, (len(SPOTS), 1)))
    return Scene(tmp_path, tmp_path / "part.obj", tmp_path / "joints.csv")


# ---------------------------------------------------------------------------- the baseline
def test_baseline_scene_plans_a_route_the_oracle_confirms(tmp_path):
    """The scenes are sound: the clean wall plate plans, and the oracle can say no (the route
    checked against a wall three times as long, which it would have to go around further)."""
    sc = make_scene(tmp_path)
    o = run_cli(sc.plan_argv())
    assert assert_invariant(o, sc.json, sc.mesh, sc.joints, 5.0) == "route"
    longer = wall_plate()
    longer.apply_scale([1.0, 3.0, 1.0])
    longer.export(str(tmp_path / "long.stl"))
    assert check_route_file(sc.json, tmp_path / "long.stl", sc.joints, 5.0)


# ---------------------------------------------------------------------------- meshes (item 1, 2)
@pytest.mark.parametrize(
    "bad",
    [
        pytest.param([np.nan] * 3, id="nan"),
        pytest.param([np.inf, 0.0, 0.0], id="inf"),
        pytest.param([0.0, -np.inf, 40.0], id="-inf"),
    ],
)
def test_non_finite_mesh_vertex_is_an_error_naming_the_file(tmp_path, bad):
    sc = _obj_scene(tmp_path, bad)
    line = assert_one_line_error(run_cli(sc.plan_argv()), BAD_INPUT, "part.obj")
    assert any(w in line.lower() for w in ("nan", "finite", "inf")), line


def test_huge_mesh_vertex_ends_in_an_error_or_a_confirmed_route(tmp_path):
    sc = _obj_scene(tmp_path, [1e300, 0.0, 40.0])
    with np.errstate(all="ignore"):
        o = run_cli(sc.plan_argv())
    if o.code == 0:  # the oracle cannot build a BVH around 1e300 either: then it is an error
        assert_invariant(o, sc.json, sc.mesh, sc.joints, 5.0)
    else:
        assert_one_line_error(o, BAD_INPUT, "part.obj")


@pytest.mark.parametrize(
    ("content", "name"),
    [
        (b"", "empty.stl"),
        (b"\x00\x01garbage" * 20, "garbage.stl"),
        (b"solid x\nendsolid x\n", "nofaces.stl"),
        (b"v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n", "degenerate.obj"),
        (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "badindex.obj"),
        (b"not a mesh", "part.txt"),
    ],
    ids=["empty", "garbage", "no-faces", "degenerate-only", "bad-face-index", "bad-suffix"],
)
def test_unreadable_meshes_are_one_line_errors_naming_the_file(tmp_path, content, name):
    (tmp_path / name).write_bytes(content)
    write_joints(tmp_path / "j.csv", SPOTS, np.tile(UP, (4, 1)))
    o = run_cli(["plan", tmp_path / name, tmp_path / "j.csv", "-o", tmp_path / "r.csv"])
    assert_one_line_error(o, BAD_INPUT, name)
    assert not (tmp_path / "r.csv").exists()


def test_closed_solid_without_approach_directions_is_not_crossed(tmp_path):
    """Joints on the top of a closed 40 mm cube, no approach directions: today the virtual
    joints land inside the steel and the legs run through it."""
    xyz = [[-10.0, 0.0, 40.0], [10.0, 0.0, 40.0], [0.0, 10.0, 40.0]]
    sc = make_scene(tmp_path, mesh=closed_box(40.0), xyz=xyz, dirs=None)
    assert_invariant(run_cli(sc.plan_argv()), sc.json, sc.mesh, sc.joints, 5.0)


@pytest.mark.parametrize(
    "mesh",
    [pytest.param(sheet, id="open-sheet"), pytest.param(plate, id="closed-plate")],
)
def test_simple_parts_plan_confirmed_routes(tmp_path, mesh):
    sc = make_scene(tmp_path, mesh=mesh(), xyz=SPOTS, dirs="up")
    assert assert_invariant(run_cli(sc.plan_argv()), sc.json, sc.mesh, sc.joints, 5.0) == "route"


# ---------------------------------------------------------------------------- units (item 3)
OFFSET = np.array([1000.0, 500.0, 800.0])


def _offset_part():
    m = wall_plate()
    m.apply_translation(OFFSET)
    return m


def test_joint_ten_metres_away_is_an_error_naming_it(tmp_path):
    sc = make_scene(tmp_path, xyz=np.vstack([SPOTS, [[10000.0, 0.0, 0.0]]]))
    line = assert_one_line_error(run_cli(sc.plan_argv()), BAD_INPUT, "J5")
    assert "mm" in line


def test_joints_in_metres_with_a_mesh_in_mm_is_an_error(tmp_path):
    sc = make_scene(tmp_path, mesh=_offset_part(), xyz=(SPOTS + OFFSET) / 1000.0)
    assert_one_line_error(run_cli(sc.plan_argv()), BAD_INPUT, "J1")


def test_wrong_scale_is_an_error(tmp_path):
    sc = make_scene(tmp_path, mesh=_offset_part(), xyz=SPOTS + OFFSET)
    assert_one_line_error(run_cli(sc.plan_argv("--scale", "10")), BAD_INPUT, "J1")


def test_right_units_plan_a_confirmed_route(tmp_path):
    """The same files read right: the mesh in mm, joints in metres declared as such fail
    today for lack of a --joint-units option, so the joints are written in mm here."""
    sc = make_scene(tmp_path, mesh=_offset_part(), xyz=SPOTS + OFFSET)
    assert assert_invariant(run_cli(sc.plan_argv()), sc.json, sc.mesh, sc.joints, 5.0) == "route"


# ---------------------------------------------------------------------------- joints (items 8, 9)
@pytest.mark.parametrize(
    ("value", "field"),
    [
        pytest.param(1e300, "x", id="1e300"),
        pytest.param(-1e300, "x", id="-1e300"),
        pytest.param("nan", "x", id="nan"),
        pytest.param("inf", "x", id="inf"),
        pytest.param("1,5", "x", id="decimal-comma-in-comma-csv"),
        pytest.param("", "x", id="empty"),
        pytest.param("0x10", "x", id="hex"),
    ],
)
def test_bad_joint_coordinates_are_one_line_errors(tmp_path, value, field):
    sc = make_scene(tmp_path)
    lines = sc.joints.read_text().splitlines()
    head = lines[0].split(",")
    row = lines[2].split(",")
    row[head.index(field)] = str(value) if not isinstance(value, float) else repr(value)
    lines[2] = ",".join(row)
    sc.joints.write_text("\n".join(lines) + "\n")
    assert_one_line_error(run_cli(sc.plan_argv()), BAD_INPUT, "joints.csv")


def test_two_joints_at_the_same_spot_warn_and_plan(tmp_path):
    xyz = np.vstack([SPOTS, SPOTS[:1]])
    sc = make_scene(tmp_path, xyz=xyz)
    o = run_cli(sc.plan_argv())
    assert assert_invariant(o, sc.json, sc.mesh, sc.joints, 5.0) == "route"
    warn = [ln for ln in o.warnings if "J1" in ln and "J5" in ln]
    assert warn, f"no warning naming J1 and J5: {o.stderr!r}"


def test_duplicate_joint_ids_are_an_error_naming_the_line(tmp_path):
    sc = make_scene(tmp_path)
    text = sc.joints.read_text().replace("J2,", "J1,")
    sc.joints.write_text(text)
    assert_one_line_error(run_cli(sc.plan_argv()), BAD_INPUT, "joints.csv", "line 3", "J1")


# ---------------------------------------------------------------------------- options (items 7, 8)
@pytest.mark.parametrize(
    ("option", "value"),
    [
        pytest.param("--seed", "-1"),
        ("--clearance", "nan"),
        ("--clearance", "0"),
        ("--clearance", "-1"),
        ("--pitch", "0"),
        ("--pitch", "inf"),
        ("--margin", "-5"),
        ("--aco", "0"),
        ("--jobs", "0"),
        ("--approach-cone", "0"),
        ("--approach-cone", "nan"),
        ("--scale", "-1"),
        ("--scale", "nan"),
        ("--length", "0"),
        ("--candidates", "0"),
    ],
)
def test_bad_option_values_are_one_line_errors_naming_the_option(tmp_path, option, value):
    sc = make_scene(tmp_path)
    o = run_cli(sc.plan_argv(option, value))
    assert_one_line_error(o, BAD_INPUT, option.lstrip("-"))
    assert not sc.csv.exists()


# ---------------------------------------------------------------------------- verify (items 3, 4)
@pytest.fixture
def planned(tmp_path) -> Scene:
    sc = make_scene(tmp_path)
    assert run_cli(sc.plan_argv()).code == 0
    return sc


@pytest.mark.parametrize(
    "value",
    [
        pytest.param("nan"),
        pytest.param("0"),
        pytest.param("-1"),
        pytest.param("inf"),
    ],
)
def test_verify_rejects_a_meaningless_clearance(planned, value):
    o = run_cli(["verify", planned.json, planned.mesh, "--clearance", value])
    assert_one_line_error(o, BAD_INPUT, "clearance")


def _edit_route(sc: Scene, name: str, edit) -> str:
    data = json.loads(sc.json.read_text())
    edit(data)
    path = sc.dir / name
    path.write_text(json.dumps(data))  # NaN is written as the token NaN, which JSON readers take
    return str(path)


@pytest.mark.parametrize(
    "value",
    [
        float("nan"),
        float("inf"),
        1e300,
    ],
)
def test_verify_rejects_non_finite_or_absurd_route_points(planned, value):
    def edit(d):
        d["legs"][0]["points"][1][0] = value

    path = _edit_route(planned, "bad.json", edit)
    with np.errstate(all="ignore"):
        o = run_cli(["verify", path, planned.mesh])
    assert o.crash is None, o.crash
    assert o.code in (BAD_INPUT, FAILURE), o.stdout
    assert len(o.err_lines) == 1 and "leg 0" in o.err_lines[0], o.stderr


def test_verify_rejects_a_route_through_the_wall(planned):
    """A leg straightened through the wall: the verifier (and the oracle) say no."""

    def edit(d):
        for leg in d["legs"]:
            if len(leg["points"]) > 4:
                leg["points"] = [leg["points"][0], leg["points"][1], leg["points"][-2],
                                 leg["points"][-1]]  # fmt: skip

    legs = json.loads(planned.json.read_text())["legs"]
    assert any(len(leg["points"]) > 4 for leg in legs), "no leg goes around the wall"
    path = _edit_route(planned, "through.json", edit)
    assert check_route_file(path, planned.mesh, planned.joints, 5.0)
    o = run_cli(["verify", path, planned.mesh])
    assert_one_line_error(o, FAILURE, "leg")


@pytest.mark.parametrize("args", [["--scale", "0.5"], ["other"]], ids=["other-scale", "other-mesh"])
def test_verify_refuses_a_route_against_another_mesh_or_scale(planned, args):
    """Both the half-size part and the plate without its wall leave the route free: only the
    route's record of the mesh and scale can tell."""
    mesh = planned.mesh
    if args == ["other"]:
        mesh = planned.dir / "other.stl"
        plate().export(str(mesh))  # the plate without its wall: the route is free against it
        args = []
    o = run_cli(["verify", planned.json, mesh, *args])
    assert o.crash is None and o.code in (BAD_INPUT, FAILURE), o.stdout
    assert len(o.err_lines) == 1, o.stderr


# ---------------------------------------------------------------------------- outputs (items 6, 9)
def test_missing_output_folder_is_an_error_before_planning(tmp_path):
    sc = make_scene(tmp_path)
    o = run_cli(sc.plan_argv("-o", tmp_path / "nope" / "r.csv"))
    assert_one_line_error(o, BAD_INPUT, "nope")


def test_output_that_is_a_folder_is_an_error(tmp_path):
    sc = make_scene(tmp_path)
    (tmp_path / "d.csv").mkdir()
    assert_one_line_error(run_cli(sc.plan_argv("-o", tmp_path / "d.csv")), BAD_INPUT, "d.csv")


def test_unwritable_output_folder_is_found_before_planning(tmp_path):
    """``/proc`` refuses new files even to root. The station would also fail planning (its
    joints sit on opposite sides of a closed cube, out of each other's reach): the error must
    be about the output, found first."""
    xyz = [[-20.0, 0.0, 20.0], [20.0, 0.0, 20.0]]
    sc = make_scene(tmp_path, mesh=closed_box(40.0), xyz=xyz, dirs=None)
    o = run_cli(sc.plan_argv("-o", "/proc/weldplan-route.csv"))
    assert_one_line_error(o, BAD_INPUT, "/proc/weldplan-route.csv")


def test_write_protected_output_file_is_named(tmp_path):
    sc = make_scene(tmp_path)
    sc.csv.write_text("old route\n")
    os.chmod(sc.csv, 0o444)
    o = run_cli(sc.plan_argv())
    assert o.crash is None
    named = [ln for ln in o.err_lines if "route.csv" in ln]
    assert named, f"nothing names the write-protected route.csv: {o.stderr!r}"
    if o.code != 0:
        assert_one_line_error(o, BAD_INPUT, "route.csv")
        assert sc.csv.read_text() == "old route\n"


def test_a_full_disk_in_the_middle_leaves_every_previous_output(tmp_path, monkeypatch):
    """The second output's write fails (ENOSPC): one line, exit 1, and the route CSV and JSON
    of the previous run are both as they were."""
    from weldplan.io import atomic

    sc = make_scene(tmp_path)
    sc.csv.write_text("old csv\n")
    sc.json.write_text("old json\n")
    real = atomic.os.fsync
    calls = []

    def fsync(fd):
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    o = run_cli(sc.plan_argv())
    assert_one_line_error(o, FAILURE, "space")
    assert sc.csv.read_text() == "old csv\n" and sc.json.read_text() == "old json\n"


def test_same_path_for_two_outputs_is_an_error(tmp_path):
    sc = make_scene(tmp_path)
    o = run_cli(["plan", sc.mesh, sc.joints, "-o", sc.csv, "--json", sc.csv, "--quiet"])
    assert_one_line_error(o, BAD_INPUT, "route.csv")


# ---------------------------------------------------------------------------- every scene at once
def test_scene_meshes_are_what_they_say():
    assert closed_box().is_watertight and plate().is_watertight
    assert not sheet().is_watertight
    assert isinstance(wall_plate(), trimesh.Trimesh)
