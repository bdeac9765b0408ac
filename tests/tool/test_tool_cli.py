"""The tool in the product: plan --tool, route CSV/JSON with TCP orientations, verify --tool,
the viewer's tool copies, one-line errors for bad tool input (issue 16)."""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.cli_helpers import one_line_error, run_cli
from tests.conftest import require_shared
from tests.output_check import csv_rows
from tests.route_fixtures import box_part, box_route
from weldplan.errors import EXIT_PARTIAL, InputError
from weldplan.io.export import CSV_FIELDS, POSE_FIELDS, to_csv_text
from weldplan.tool import WeldPose, WeldPoses, arc_torch
from weldplan.tool.model import load_tool, parse_tcp
from weldplan.tool.poses import waypoint_quaternions, weld_rows

#: the box scene with a fifth joint E 2 mm beside the wall, where the torch cannot stand
JOINTS_CSV = "id,x,y,z\nA,-40,0,0\nB,40,0,0\nC,-40,60,0\nD,40,-30,0\nE,-3,0,5\n"


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """``weldplan plan box joints --tool torch.stl --tcp 0,0,0,0,0,0`` once for the module."""
    tmp = tmp_path_factory.mktemp("toolcli")
    box_part().export(tmp / "box.stl")
    (tmp / "joints.csv").write_text(JOINTS_CSV)
    arc_torch(stickout=3).mesh.export(tmp / "torch.stl")  # TCP within 5 mm of the mesh
    argv = [
        "plan", str(tmp / "box.stl"), str(tmp / "joints.csv"), "--margin", "50", "--quiet",
        "-o", str(tmp / "r.csv"), "--json", str(tmp / "r.json"), "--html", str(tmp / "r.html"),
        "--tool", str(tmp / "torch.stl"), "--tcp", "0,0,0,0,0,0",
    ]  # fmt: skip
    rc = run_cli(argv)
    return tmp, rc


def test_plan_with_tool_reports_the_weld_without_a_pose_and_exits_partial(planned):
    tmp, rc = planned
    assert rc == EXIT_PARTIAL
    d = json.loads((tmp / "r.json").read_text())
    prov = d["tool"]["provenance"]
    assert prov["file_sha256"] == hashlib.sha256((tmp / "torch.stl").read_bytes()).hexdigest()
    assert prov["tcp"] == "0,0,0,0,0,0" and prov["units"] == "mm"
    poses = WeldPoses.from_dict(d["tool"]["poses"])
    assert poses.order == tuple(d["order"])
    status = {p.id: p.status for p in poses.poses}
    assert status == {"A": "ok", "B": "ok", "C": "ok", "D": "ok", "E": "no free pose"}
    miss = poses["E"].miss
    assert miss is not None and (miss.contacts > 0 or miss.distance < 5.0)
    assert poses["E"].quaternion is None
    # the exit test judged the picks (on by default): every ok weld at least once
    assert poses.stats["exit_calls"] >= 4 and isinstance(poses.stats["exit_vetoed"], dict)


def test_no_exit_check_turns_the_exit_test_off():
    from weldplan.cli import build_parser

    base = ["plan", "b.stl", "j.csv", "-o", "r.csv", "--tool", "t.stl"]
    assert build_parser().parse_args(base).exit_check is True
    assert build_parser().parse_args([*base, "--no-exit-check"]).exit_check is False


def test_plan_with_tool_csv_has_orientations_at_the_verified_weld_poses_only(planned):
    tmp, _ = planned
    rows = csv_rows(tmp / "r.csv")
    assert tuple(rows[0]) == CSV_FIELDS + POSE_FIELDS
    d = json.loads((tmp / "r.json").read_text())
    poses = WeldPoses.from_dict(d["tool"]["poses"])
    for r in rows:
        if r["kind"] == "weld":
            p = poses[r["joint_id"]]
            assert r["status"] == p.status
            if p.ok:
                q = [float(r[k]) for k in ("qw", "qx", "qy", "qz")]
                np.testing.assert_allclose(q, p.quaternion, atol=1e-6)
            else:
                assert [r[k] for k in ("qw", "qx", "qy", "qz")] == ["", "", "", ""]
        else:
            assert r["status"] == ""  # nothing verified the tool between welds here
            assert [r[k] for k in ("qw", "qx", "qy", "qz")] == ["", "", "", ""]


def test_verify_with_the_same_tool_rechecks_the_poses(planned, capsys):
    tmp, _ = planned
    capsys.readouterr()
    rc = run_cli(["verify", str(tmp / "r.json"), str(tmp / "box.stl"),
              "--tool", str(tmp / "torch.stl"), "--tcp", "0,0,0,0,0,0"])  # fmt: skip
    out = capsys.readouterr().out
    assert rc == EXIT_PARTIAL, out
    (poses_line,) = [ln for ln in out.splitlines() if ln.startswith("tool poses ok")]
    assert "4 / 5 welds with a free pose" in poses_line and "E" in poses_line


def test_verify_refuses_a_route_planned_with_another_tool(planned, capsys):
    tmp, _ = planned
    capsys.readouterr()
    rc = run_cli(["verify", str(tmp / "r.json"), str(tmp / "box.stl"),
              "--tool", str(tmp / "torch.stl"), "--tcp", "0,0,1,0,0,0"])  # fmt: skip
    assert rc == 2
    line = one_line_error(capsys)
    assert "planned with another tool" in line and "tcp" in line


def test_verify_compares_the_resolved_tcp_not_its_spelling(planned, capsys):
    """A URDF tool's TCP written as nothing (its last fixed joint) or as that joint's name is one
    TCP, so verify accepts either; another joint (1 mm along z) is another tool. The URDF wraps
    the planned mesh tool (the TCP joint at the mesh origin): its provenance replaces the route's,
    as ``plan --tool tool.urdf`` would record it."""
    tmp, _ = planned
    (tmp / "tool.urdf").write_text(
        '<robot name="t"><link name="root"><collision><geometry><mesh filename="torch.stl" '
        'scale="0.001 0.001 0.001"/></geometry></collision></link><link name="side"/>'
        '<link name="tip"/><joint name="side_joint" type="fixed"><origin xyz="0 0 0.001"/>'
        '<parent link="root"/><child link="side"/></joint><joint name="tip_joint" type="fixed">'
        '<origin xyz="0 0 0"/><parent link="root"/><child link="tip"/></joint></robot>'
    )
    _, prov = load_tool(tmp / "tool.urdf")
    assert prov["tcp"] is None  # planned without --tcp: the last fixed joint, tip_joint
    d = json.loads((tmp / "r.json").read_text())
    d["tool"]["provenance"] = prov
    (tmp / "urdf_route.json").write_text(json.dumps(d))
    base = ["verify", str(tmp / "urdf_route.json"), str(tmp / "box.stl"),
            "--tool", str(tmp / "tool.urdf")]  # fmt: skip
    for tcp in ([], ["--tcp", "tip_joint"], ["--tcp", "tip"]):  # the joint or its child link
        capsys.readouterr()
        assert run_cli(base + tcp) == EXIT_PARTIAL, (tcp, capsys.readouterr())
    capsys.readouterr()
    assert run_cli(base + ["--tcp", "side_joint"]) == 2
    line = one_line_error(capsys)
    assert "planned with another tool" in line and "tcp None (route) != 'side_joint'" in line


def test_tip_cone_narrows_a_mesh_tools_contact_zone_and_verify_must_agree(planned, capsys):
    """A mesh tool has no tip cone (the whole contact sphere may touch); ``--tip-cone 15`` keeps
    only the wire's cone: the nozzle's mouth, inside the sphere but off the axis, is no longer
    in the zone. A route planned without it is refused by a
    verify with it (another tool definition)."""
    from weldplan.commands._tool import tool_from_args

    tmp, _ = planned
    ns = dataclasses.make_dataclass("Args", ["tool", "tcp", "tool_units", "tool_mesh", "tip_cone"])
    plain, prov = tool_from_args(ns(str(tmp / "torch.stl"), "0,0,0,0,0,0", None, None, None))
    cone, prov_c = tool_from_args(ns(str(tmp / "torch.stl"), "0,0,0,0,0,0", None, None, 15.0))
    assert plain.tip_cone is None and cone.tip_cone == 15.0 and prov_c["tip_cone"] == 15.0
    v = plain.vertices
    r = np.linalg.norm(v, axis=1)
    off_axis = np.degrees(np.arccos(np.clip(-v[:, 2] / np.maximum(r, 1e-9), -1, 1)))
    rim = v[(r < 20.0) & (off_axis > 30.0)]  # the nozzle's mouth, near the TCP but off its axis
    assert len(rim) and plain.in_zone(rim, 20.0).all() and not cone.in_zone(rim, 20.0).any()
    capsys.readouterr()
    rc = run_cli(["verify", str(tmp / "r.json"), str(tmp / "box.stl"), "--tool",
                  str(tmp / "torch.stl"), "--tcp", "0,0,0,0,0,0", "--tip-cone", "15"])  # fmt: skip
    assert rc == 2 and "tip_cone None (route) != 15.0 (given)" in one_line_error(capsys)


def test_verify_catches_a_tampered_pose(planned, capsys):
    tmp, _ = planned
    d = json.loads((tmp / "r.json").read_text())
    for p in d["tool"]["poses"]["poses"]:
        if p["id"] == "A":
            # TCP +z along part +x: the torch lies along the floor, through it beyond the zone
            p["quaternion"] = [0.5**0.5, 0.0, 0.5**0.5, 0.0]
    bad = tmp / "tampered.json"
    bad.write_text(json.dumps(d))
    capsys.readouterr()
    rc = run_cli(["verify", str(bad), str(tmp / "box.stl"),
              "--tool", str(tmp / "torch.stl"), "--tcp", "0,0,0,0,0,0"])  # fmt: skip
    assert rc == 1
    err = capsys.readouterr().err
    assert "tool poses" in err and "weld A" in err


def test_viewer_draws_the_tool_and_the_weld_without_a_pose(planned):
    import meshcat
    from meshcat.servers.tree import find_node

    from weldplan.io.export import read_route
    from weldplan.viz.viewer import RecordingWindow, build_scene

    tmp, _ = planned
    route = read_route(tmp / "r.json")
    tool, _ = load_tool(tmp / "torch.stl", tcp="0,0,0,0,0,0")
    window = RecordingWindow()
    slider = build_scene(meshcat.Visualizer(window=window), route, box_part(), tool=tool)

    def node(path):
        return find_node(window.tree, [p for p in path.split("/") if p])

    root = "meshcat/weldplan/tool"
    assert sorted(node(root)) == ["gun", "path", "tool_miss"]  # one tool, not one a weld
    assert list(node(f"{root}/tool_miss")) == ["E"]
    import umsgpack

    # the slider moves the one tool through the welds with a pose, in the route's order
    assert slider.path == f"/{root}/gun" and set(slider.ids) == {"A", "B", "C", "D"}
    assert list(slider.ids) == [j for j in route.order if j != "E"]
    for jid, cols in zip(slider.ids, slider.matrices, strict=True):
        T = np.array(cols).reshape(4, 4).T  # column-major, as meshcat sends it
        pose = route_pose(route, jid)
        np.testing.assert_allclose(T[:3, 3], pose.position, atol=1e-9)
        np.testing.assert_allclose(T[:3, :3], pose.rotation(), atol=1e-9)
    matrix = umsgpack.unpackb(node(f"{root}/gun").transform)["matrix"]
    T = np.array(matrix).reshape(4, 4).T  # the page opens with the tool at the first weld
    np.testing.assert_allclose(T, np.array(slider.matrices[0]).reshape(4, 4).T, atol=1e-4)
    assert (tmp / "r.html").stat().st_size > 0


def route_pose(route, jid) -> WeldPose:
    return WeldPoses.from_dict(route.tool["poses"])[jid]


def test_slerp_along_the_route_follows_arc_length():
    route = box_route()  # A -> C -> B
    qa = Rotation.from_euler("x", 180, degrees=True)
    qc = Rotation.from_euler("xy", [180, 40], degrees=True)
    qb = Rotation.from_euler("xz", [180, 90], degrees=True)

    def wxyz(r):
        return tuple(np.roll(r.as_quat(), 1))

    poses = WeldPoses(
        poses=tuple(
            WeldPose(j, "ok", tuple(route.joint_xyz[route.index_of(j)]), (0, 0, -1), wxyz(r))
            for j, r in zip(("A", "C", "B"), (qa, qc, qb), strict=True)
        ),
        tool="t",
        total_rotation=0.0,
    )
    q = waypoint_quaternions(route, poses)
    W = route.waypoints()
    s = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(W, axis=0), axis=1))])
    rows = weld_rows(route)
    assert rows.tolist() == [0, 3, 7]
    for (a, b), (ra, rb) in zip(((0, 3), (3, 7)), ((qa, qc), (qc, qb)), strict=True):
        total = (ra.inv() * rb).magnitude()
        for k in range(a, b + 1):
            rk = Rotation.from_quat(np.roll(q[k], -1))
            frac = (s[k] - s[a]) / (s[b] - s[a])
            assert (ra.inv() * rk).magnitude() == pytest.approx(frac * total, abs=1e-9)
            assert (rk.inv() * rb).magnitude() == pytest.approx((1 - frac) * total, abs=1e-9)
    # the CSV carries them, and a route without poses keeps its columns and JSON
    with_poses = dataclasses.replace(route, tool={"provenance": {}, "poses": poses.to_dict()})
    text = to_csv_text(with_poses)
    assert text.splitlines()[0] == ",".join(CSV_FIELDS + POSE_FIELDS)
    assert to_csv_text(route).splitlines()[0] == ",".join(CSV_FIELDS)
    assert "tool" not in json.loads(route.to_json())
    assert type(route).from_json(with_poses.to_json()) == with_poses


def test_parse_tcp_errors_name_the_field():
    assert parse_tcp("1,2,3,0,90,0") == [1.0, 2.0, 3.0, 0.0, 90.0, 0.0]
    for bad in ("1,2,3", "1,2,3,4,5,6,7", "1,2,3,a,5,6", "1,2,nan,0,0,0", "1,2,3,inf,0,0"):
        with pytest.raises(InputError) as e:
            parse_tcp(bad)
        assert e.value.field == "--tcp"


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--tool", "{tmp}/missing.urdf"], "no such tool file"),
        (["--tool", "{tmp}/torch.stl"], "needs --tcp"),
        (["--tool", "{tmp}/torch.stl", "--tcp", "1,2,3"], "six comma-separated"),
        (["--tool", "{tmp}/torch.stl", "--tcp", "0,0,nan,0,0,0"], "finite"),
        (["--tool", "{tmp}/torch.stl", "--tcp", "0,0,0,0,0,0", "--tool-units", "m"], "units"),
        (["--tool", "{tmp}/torch.stl", "--tcp", "0,0,900,0,0,0"], "outside"),
        (["--tool", "{tmp}/nofixed.urdf"], "no fixed joint"),
        (["--tool", "{tmp}/cad.urdf"], "--tool-mesh"),
        (["--tcp", "0,0,0,0,0,0"], "--tcp needs --tool"),
        (["--tip-cone", "15"], "--tip-cone needs --tool"),
        (["--tool", "{tmp}/torch.stl", "--tcp", "0,0,0,0,0,0", "--tip-cone", "0"], "(0, 90]"),
        (["--tool", "{tmp}/torch.stl", "--tcp", "0,0,0,0,0,0", "--tool-cone", "120"], "90"),
    ],
)
def test_bad_tool_input_is_one_line_before_any_planning(tmp_path, capsys, extra, words):
    box_part().export(tmp_path / "box.stl")
    (tmp_path / "joints.csv").write_text(JOINTS_CSV)
    arc_torch(stickout=3).mesh.export(tmp_path / "torch.stl")
    (tmp_path / "nofixed.urdf").write_text('<robot name="r"><link name="a"/></robot>')
    (tmp_path / "cad.urdf").write_text(
        '<robot name="r"><link name="root"><visual><geometry><mesh filename="gone.stl"/>'
        '</geometry></visual></link><link name="tip"/><joint name="tip" type="fixed">'
        '<origin xyz="0 0 0" rpy="0 0 0"/><parent link="root"/><child link="tip"/></joint>'
        "</robot>"
    )
    argv = ["plan", str(tmp_path / "box.stl"), str(tmp_path / "joints.csv"), "--quiet",
            "-o", str(tmp_path / "r.csv")]  # fmt: skip
    rc = run_cli(argv + [a.format(tmp=tmp_path) for a in extra])
    assert rc == 2
    assert words in one_line_error(capsys)
    assert not (tmp_path / "r.csv").exists()


def test_the_shared_gun_urdf_is_read_with_its_stl_and_recorded():
    d = require_shared("tools", "spot_welding_gun")
    tool, prov = load_tool(d / "spot_welding_gun.urdf")
    assert prov["mesh"].endswith("spot_welding_gun.stl") and prov["units"] == "m"
    stl = (d / "spot_welding_gun.stl").read_bytes()
    assert prov["mesh_sha256"] == hashlib.sha256(stl).hexdigest()
    np.testing.assert_allclose(tool.extent.max(), 827.1, atol=0.5)  # the gun in mm, not m
    # the same URDF with another mesh unit is another tool: verify would refuse it
    with pytest.raises(InputError, match="units"):
        load_tool(d / "spot_welding_gun.urdf", mesh=d / "spot_welding_gun.stl", units="mm")


def test_view_html_with_the_tool_and_another_tool_refused(planned, capsys):
    tmp, _ = planned
    page = tmp / "view.html"
    base = ["view", str(tmp / "r.json"), str(tmp / "box.stl"), "--html", str(page)]
    assert run_cli(base + ["--tool", str(tmp / "torch.stl"), "--tcp", "0,0,0,0,0,0"]) == 0
    assert page.stat().st_size > 0
    capsys.readouterr()
    assert run_cli(base + ["--tool", str(tmp / "torch.stl"), "--tcp", "0,0,2,0,0,0"]) == 2
    assert "another tool" in one_line_error(capsys)


@pytest.mark.slow
def test_headless_chromium_draws_the_tool_and_the_weld_without_a_pose(planned, tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image

    from tests.test_viewer import _chromium, _run_chromium
    from weldplan.io.export import read_route
    from weldplan.viz.viewer import write_html

    assert _chromium()
    tmp, _ = planned
    route = read_route(tmp / "r.json")
    # the tool and the misses only: the transitions (animated, framed with the route) are
    # tested in test_tool_viewer.py
    route = dataclasses.replace(
        route, tool={k: v for k, v in route.tool.items() if k != "transitions"}
    )
    tool, _ = load_tool(tmp / "torch.stl", tcp="0,0,0,0,0,0")
    without = dataclasses.replace(route, tool={})
    shots = {}
    for name, r, t in (("tool", route, tool), ("plain", without, None)):
        page = write_html(r, box_part(), tmp_path / f"{name}.html", tool=t)
        png = tmp_path / f"{name}.png"
        shot = _run_chromium(tmp_path, f"--screenshot={png}", page.resolve().as_uri())
        assert shot.returncode == 0 and png.exists(), shot.stderr[-2000:]
        shots[name] = np.asarray(Image.open(png).convert("RGB"), dtype=float)

    def red(img):  # the point-tip page draws visited joints red; with poses only E stays red
        r, g, b = (img[..., k] for k in range(3))
        return int(((r > g + 50) & (r > b + 30)).sum())

    def purple(img):  # only the tool is purple (0x8E44AD)
        r, g, b = (img[..., k] for k in range(3))
        return int(((b > g + 40) & (r > g + 20)).sum())

    # the one tool (at the first weld) changes the view; E keeps its red, with a halo
    assert (np.abs(shots["tool"] - shots["plain"]).max(axis=-1) > 30).mean() > 0.02
    assert purple(shots["tool"]) > 10 * purple(shots["plain"]) + 200  # (a leg is violet)
    assert red(shots["plain"]) >= 30 and red(shots["tool"]) >= 30


def test_verify_rechecks_the_transitions_and_catches_a_tampered_one(planned, capsys):
    tmp, _ = planned
    d = json.loads((tmp / "r.json").read_text())
    trans = d["tool"]["transitions"]["transitions"]
    free = [t for t in trans if t["status"] != "blocked"]
    assert free, "the box station has free transitions"
    capsys.readouterr()
    argv = ["verify", None, str(tmp / "box.stl"), "--tool", str(tmp / "torch.stl"),
            "--tcp", "0,0,0,0,0,0"]  # fmt: skip
    argv[1] = str(tmp / "r.json")
    run_cli(argv)
    assert "tool transitions ok" in capsys.readouterr().out
    # send the first free transition's second waypoint 50 mm under the floor
    free[0]["positions"][1][2] = -50.0
    bad = tmp / "tampered_transition.json"
    bad.write_text(json.dumps(d))
    argv[1] = str(bad)
    assert run_cli(argv) == 1
    err = capsys.readouterr().err
    assert "tool transitions" in err and f"{free[0]['from']}->{free[0]['to']}" in err
