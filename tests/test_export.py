"""Exports: CSV rows, JSON, robot posts, and atomic writes that never clobber a good file."""

from __future__ import annotations

import csv
import json
import os
import re

import numpy as np
import pytest

from tests.route_fixtures import SPOTS, box_part, box_route
from weldplan.errors import InputError, WeldplanError
from weldplan.io import atomic, export
from weldplan.io.export import (
    POSTS,
    euler_zyx_deg,
    quaternion,
    read_route,
    register_post,
    render_post,
    tool_frame,
    write_csv,
    write_json,
    write_post,
    write_text_atomic,
)
from weldplan.io.timings import split_timings, timings_path


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_csv_rows(tmp_path):
    write_csv(box_route(directions=True), tmp_path / "r.csv")
    rows = _rows(tmp_path / "r.csv")
    assert list(rows[0]) == list(export.CSV_FIELDS)
    assert [r["kind"] for r in rows] == ["weld", "via", "via", "weld", "via", "via", "via", "weld"]
    assert [r["joint_id"] for r in rows if r["kind"] == "weld"] == ["A", "C", "B"]
    assert [int(r["step"]) for r in rows] == list(range(8))
    weld = [r for r in rows if r["kind"] == "weld"]
    np.testing.assert_allclose([[float(r[k]) for k in "xyz"] for r in weld], SPOTS[[0, 2, 1]])
    assert all(r["tool_z"] == "1.000000" for r in weld)  # as the joints CSV gave it
    assert all(r["tool_x"] == "" and r["joint_id"] == "" for r in rows if r["kind"] == "via")


def test_csv_without_directions_leaves_tool_empty(tmp_path):
    write_csv(box_route(), tmp_path / "r.csv")
    assert all(r["tool_x"] == r["tool_y"] == r["tool_z"] == "" for r in _rows(tmp_path / "r.csv"))


def test_json_round_trip_through_files(tmp_path):
    r = box_route(directions=True)
    write_json(r, tmp_path / "r.json")
    back = read_route(tmp_path / "r.json")
    assert json.loads(back.to_json()) == split_timings(json.loads(r.to_json()))[0]
    write_json(back, tmp_path / "again.json")  # nothing left to move: the same bytes
    assert (tmp_path / "again.json").read_bytes() == (tmp_path / "r.json").read_bytes()


def test_measured_times_leave_the_route_json_for_the_timings_file():
    d = {
        "settings": {"time_s": 10.0, "seconds": 3},  # settings: not measured, they stay
        "stats": {
            "seconds": {"local": 0.4, "total": 0.6},
            "local_paths": {"1-2": {"seconds": 0.01, "length": 5.0}},
            "pairs": 7,
            "ompl": {"runs": 2.0, "s": 1.5, "wall_s": 3.0, "checks": 90.0},
        },
        "tool": {"poses": {"stats": {"choose_s": 2.0, "candidates": 8}}, "order": ["a"]},
        "runs": [{"stats": {"seconds_total": 1.0}}, {"stats": {"n": 1}}],
    }
    keep, moved = split_timings(d)
    assert keep == {
        "settings": {"time_s": 10.0, "seconds": 3},
        "stats": {"local_paths": {"1-2": {"length": 5.0}}, "pairs": 7,
                  "ompl": {"runs": 2.0, "checks": 90.0}},
        "tool": {"poses": {"stats": {"candidates": 8}}, "order": ["a"]},
        "runs": [{"stats": {}}, {"stats": {"n": 1}}],
    }  # fmt: skip
    assert moved == {
        "stats": {"seconds": {"local": 0.4, "total": 0.6},
                  "local_paths": {"1-2": {"seconds": 0.01}}, "ompl": {"s": 1.5, "wall_s": 3.0}},
        "tool": {"poses": {"stats": {"choose_s": 2.0}}},
        "runs": [{"stats": {"seconds_total": 1.0}}, None],
    }  # fmt: skip
    assert timings_path("out/route.json").as_posix() == "out/route.timings.json"


def test_read_route_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{\n  not json")
    with pytest.raises(InputError, match=r"bad.json, line 2: not valid JSON"):
        read_route(bad)
    other = tmp_path / "other.json"
    other.write_text('{"format": "x"}')
    with pytest.raises(InputError, match="other.json: not a valid weldplan route"):
        read_route(other)


def test_rapid_post(tmp_path):
    r = box_route()
    write_post(r, tmp_path / "r.mod", "rapid", box_part())
    text = (tmp_path / "r.mod").read_text()
    assert text.startswith("MODULE weldplan_route") and "ENDMODULE" in text
    targets = re.findall(r"CONST robtarget (p\d{4}):=\[\[([^\]]*)\],\[([^\]]*)\]", text)
    assert len(targets) == 8 + 2  # the route's rows plus approach and retreat
    moves = re.findall(r"(MoveJ|MoveL) (p\d{4}),(\w+),(\w+),", text)
    assert [m[0] for m in moves] == ["MoveJ"] + ["MoveL"] * 9
    assert [m[1] for m in moves] == [t[0] for t in targets]
    # welds, the approach and the retreat stop exactly; the vias 10 mm above the floor fly by
    # with z1, the largest standard zone within their 5 mm free margin (less round-off)
    assert [m[3] for m in moves] == ["fine", "fine", "z1", "z1", "fine"] + ["z1"] * 3 + ["fine"] * 2
    # the first move goes to A's approach point, the second onto A
    assert [float(v) for v in targets[0][1].split(",")] == [-40.0, 0.0, 10.0]
    assert [float(v) for v in targets[1][1].split(",")] == [-40.0, 0.0, 0.0]
    # tool straight down: quaternion [0, 1, 0, 0]
    assert targets[1][2] == "0.000000,1.000000,0.000000,0.000000"
    # with approach directions out of the floor (+z) the torch points into it: the same
    with_dirs = render_post(box_route(directions=True), "rapid", box_part())
    assert with_dirs.count("[0.000000,1.000000,0.000000,0.000000]") == 10
    assert "-0.000" not in text


def test_krl_post():
    text = render_post(box_route(), "krl", box_part())
    assert text.startswith("DEF weldplan_route()") and text.rstrip().endswith("END")
    moves = re.findall(r"^  (PTP|LIN) \{X ([-\d.]+), Y ([-\d.]+), Z ([-\d.]+)", text, re.M)
    assert len(moves) == 10 and moves[0][0] == "PTP"
    assert text.count("; weld joint") == 3


def test_the_point_tip_posts_take_the_station_name():
    """A station with a name names the point-tip program after it (RAPID's module, KRL's
    program), as the robot's programs are; without one, ``weldplan_route``."""
    from weldplan.station.outputs import post_name_option

    assert post_name_option("rapid", "door_left") == {"module": "door_left"}
    assert post_name_option("krl", "door_left") == {"program": "door_left"}
    assert post_name_option("rapid", None) == {}
    r, part = box_route(), box_part()
    rapid = render_post(r, "rapid", part, **post_name_option("rapid", "door_left"))
    krl = render_post(r, "krl", part, **post_name_option("krl", "door_left"))
    assert rapid.startswith("MODULE door_left\n") and krl.startswith("DEF door_left()")


def test_posts_are_pluggable():
    @register_post("xyz-test", ".txt", "bare coordinates")
    def _xyz(route, **options):
        return "".join(f"{x:.1f} {y:.1f} {z:.1f}\n" for x, y, z in route.waypoints())

    try:
        assert render_post(box_route(), "xyz-test").splitlines()[0] == "-40.0 0.0 0.0"
        assert POSTS["xyz-test"].suffix == ".txt"
    finally:
        POSTS.pop("xyz-test")
    with pytest.raises(WeldplanError, match="unknown post 'nope'"):
        render_post(box_route(), "nope")


@pytest.mark.parametrize("d", [[0, 0, -1], [0, 0, 1], [1, 0, 0], [0.6, 0, 0.8], [0.3, -0.4, 0.866]])
def test_tool_frame_quaternion_and_euler_agree(d):
    d = np.asarray(d, float) / np.linalg.norm(d)
    R = tool_frame(d)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(R[:, 2], d, atol=1e-12)
    w, x, y, z = quaternion(R)
    Rq = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    np.testing.assert_allclose(Rq, R, atol=1e-9)
    A, B, C = np.radians(euler_zyx_deg(R))
    Rz = np.array([[np.cos(A), -np.sin(A), 0], [np.sin(A), np.cos(A), 0], [0, 0, 1]])
    Ry = np.array([[np.cos(B), 0, np.sin(B)], [0, 1, 0], [-np.sin(B), 0, np.cos(B)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(C), -np.sin(C)], [0, np.sin(C), np.cos(C)]])
    np.testing.assert_allclose(Rz @ Ry @ Rx, R, atol=1e-9)


def test_atomic_write_replaces_whole_file(tmp_path):
    p = tmp_path / "out.csv"
    p.write_text("old")
    os.chmod(p, 0o640)
    write_text_atomic(p, "new")
    assert p.read_text() == "new"
    assert (p.stat().st_mode & 0o777) == 0o640
    assert [f.name for f in tmp_path.iterdir()] == ["out.csv"]


def test_failed_write_leaves_the_old_file_and_no_temp(tmp_path, monkeypatch):
    p = tmp_path / "route.csv"
    p.write_text("good")

    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(atomic.os, "fsync", boom)
    with pytest.raises(OSError, match="disk full"):
        write_csv(box_route(), p)
    assert p.read_text() == "good"
    assert [f.name for f in tmp_path.iterdir()] == ["route.csv"]


def test_failed_render_leaves_the_old_file(tmp_path):
    p = tmp_path / "route.mod"
    p.write_text("good")
    with pytest.raises(WeldplanError):
        write_post(box_route(), p, "no-such-post")
    assert p.read_text() == "good"


def test_missing_folder_is_a_user_error(tmp_path):
    with pytest.raises(WeldplanError, match="does not exist"):
        write_text_atomic(tmp_path / "nope" / "r.csv", "x")
