"""The tool's verified path as CSV (``plan --tool-csv``, weldplan.io.tool_csv): the rows are the
transitions the swept check proved free, so the path read back from the file passes the
independent re-check; a blocked transition is a ``blocked`` row, never a motion."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.cli_helpers import one_line_error, run_cli
from tests.output_check import csv_rows
from tests.route_fixtures import box_part
from weldplan.io.tool_csv import FIELDS, tool_path_csv, tool_path_rows
from weldplan.tool import WeldPose, WeldPoses, arc_torch
from weldplan.tool.transitions import BLOCKED, DIRECT, ToolPath, Transition
from weldplan.tool.verify import verify_sweeps

JOINTS_CSV = "id,x,y,z\nA,-40,0,0\nB,40,0,0\nC,-40,60,0\nD,40,-30,0\n"
TCP = "0,0,0,0,0,0"


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """``plan box joints --tool torch.stl --tool-csv t.csv`` once for the module."""
    tmp = tmp_path_factory.mktemp("toolpathcsv")
    box_part().export(tmp / "box.stl")
    (tmp / "joints.csv").write_text(JOINTS_CSV)
    arc_torch(stickout=3).mesh.export(tmp / "torch.stl")
    argv = [
        "plan", str(tmp / "box.stl"), str(tmp / "joints.csv"), "--margin", "50", "--quiet",
        "-o", str(tmp / "r.csv"), "--json", str(tmp / "r.json"),
        "--tool", str(tmp / "torch.stl"), "--tcp", TCP, "--tool-csv", str(tmp / "t.csv"),
    ]  # fmt: skip
    return tmp, run_cli(argv)


def _read_path(csv_path):
    """The :class:`ToolPath` a reader of the CSV replays: a transition from each weld row to the
    next, through the rows between them."""
    rows = csv_rows(csv_path)  # its "#" lines (what produced it, what was verified) skipped
    welds = [k for k, r in enumerate(rows) if r["kind"] == "weld"]
    order = tuple(rows[k]["joint_id"] for k in welds)
    trans = []
    for a, b in zip(welds, welds[1:], strict=False):
        seg = rows[a : b + 1]
        if any(r["kind"] == "blocked" for r in seg):
            P = np.array([[float(seg[i][c]) for c in "xyz"] for i in (0, -1)])
            Q = np.array([[float(seg[i][c]) for c in ("qw", "qx", "qy", "qz")] for i in (0, -1)])
            trans.append(Transition(order[len(trans)], order[len(trans) + 1], P, Q, ("move",),
                                    BLOCKED))  # fmt: skip
            continue
        P = np.array([[float(r[c]) for c in "xyz"] for r in seg])
        Q = np.array([[float(r[c]) for c in ("qw", "qx", "qy", "qz")] for r in seg])
        kinds = tuple(r["kind"] for r in seg[1:-1]) + ("approach",)
        trans.append(Transition(order[len(trans)], order[len(trans) + 1], P, Q, kinds,
                                seg[1]["status"] if len(seg) > 2 else DIRECT))  # fmt: skip
    return rows, ToolPath(order=order, transitions=tuple(trans))


def test_the_tool_csv_replays_the_verified_transitions(planned):
    tmp, rc = planned
    assert rc == 0
    d = json.loads((tmp / "r.json").read_text())
    path = ToolPath.from_dict(d["tool"]["transitions"])
    poses = WeldPoses.from_dict(d["tool"]["poses"])
    rows, back = _read_path(tmp / "t.csv")
    assert tuple(rows[0]) == FIELDS
    assert [int(r["step"]) for r in rows] == list(range(len(rows)))
    assert back.order == path.order  # the tool's order, not the point-tip route's
    for t, u in zip(path.transitions, back.transitions, strict=True):
        np.testing.assert_allclose(u.positions, t.positions, atol=1e-4)  # 4 decimals
        same_sign = np.where(t.quaternions[:, :1] < 0, -t.quaternions, t.quaternions)
        np.testing.assert_allclose(u.quaternions, same_sign, atol=1e-6)
    for r in rows:
        if r["kind"] == "weld":
            p = poses[r["joint_id"]]
            assert r["status"] == "ok"
            np.testing.assert_allclose([float(r[c]) for c in "xyz"], p.position, atol=1e-4)
        assert float(r["qw"]) >= 0.0
    tool = arc_torch(stickout=3)
    check = verify_sweeps(back, poses, box_part(), tool)
    assert check.ok and check.checked == len(path.transitions), check.failures


def test_a_tampered_row_fails_the_independent_recheck(planned, tmp_path):
    tmp, _ = planned
    d = json.loads((tmp / "r.json").read_text())
    poses = WeldPoses.from_dict(d["tool"]["poses"])
    lines = [ln for ln in (tmp / "t.csv").read_text().splitlines() if not ln.startswith("#")]
    k = next(i for i, ln in enumerate(lines[1:], 1) if ",weld," not in ln)
    cells = lines[k].split(",")
    cells[5] = "-50.0"  # z: under the box's top, inside the part
    lines[k] = ",".join(cells)
    (tmp_path / "bad.csv").write_text("\n".join(lines) + "\n")
    _, back = _read_path(tmp_path / "bad.csv")
    assert not verify_sweeps(back, poses, box_part(), arc_torch(stickout=3)).ok


def _pose(i, x):
    return WeldPose(id=i, status="ok", position=(x, 0.0, 0.0), approach=(0.0, 0.0, -1.0),
                    quaternion=(0.0, 1.0, 0.0, 0.0))  # fmt: skip


def test_a_blocked_transition_is_one_blocked_row_and_no_motion():
    poses = WeldPoses((_pose("A", 0.0), _pose("B", 100.0), _pose("C", 200.0)), "t", 0.0)
    q = np.array([[0.6, 0.8, 0.0, 0.0]] * 4)
    t1 = Transition("A", "B", np.array([[0, 0, 0], [0, 0, 50], [100, 0, 50], [100, 0, 0.0]]),
                    -q, ("retract", "move", "approach"), DIRECT)  # fmt: skip
    t2 = Transition("B", "C", np.array([[100, 0, 0], [150, 0, -40], [200, 0, 0.0]]), q[:3],
                    ("move", "move"), BLOCKED, reason="every exit blocked")  # fmt: skip
    rows = tool_path_rows(ToolPath(("A", "B", "C"), (t1, t2)), poses)
    assert [r["kind"] for r in rows] == ["weld", "retract", "move", "weld", "blocked", "weld"]
    assert [r["joint_id"] for r in rows if r["kind"] == "weld"] == ["A", "B", "C"]
    blocked = rows[4]
    assert blocked["status"] == "blocked" and "x" not in blocked  # the unverified points go
    assert rows[1]["qw"] == 0.6 and rows[1]["qx"] == 0.8  # one sign: -q written as q
    text = tool_path_csv(ToolPath(("A", "B", "C"), (t1, t2)), poses)
    assert text.splitlines()[5] == "4,blocked,,,,,,,,,blocked"


def test_a_transition_that_does_not_end_at_its_weld_is_refused():
    poses = WeldPoses((_pose("A", 0.0), _pose("B", 100.0)), "t", 0.0)
    q = np.array([[0.0, 1.0, 0.0, 0.0]] * 2)
    t = Transition("A", "B", np.array([[0, 0, 0], [90, 0, 0.0]]), q, ("move",), DIRECT)
    with pytest.raises(ValueError, match="does not end at weld B"):
        tool_path_rows(ToolPath(("A", "B"), (t,)), poses)


def test_tool_csv_without_a_tool_is_one_line(tmp_path, capsys):
    box_part().export(tmp_path / "box.stl")
    (tmp_path / "joints.csv").write_text(JOINTS_CSV)
    rc = run_cli(["plan", str(tmp_path / "box.stl"), str(tmp_path / "joints.csv"), "-o",
                  str(tmp_path / "r.csv"), "--tool-csv", str(tmp_path / "t.csv")])  # fmt: skip
    assert rc != 0
    assert "--tool-csv needs --tool" in one_line_error(capsys)
    assert not (tmp_path / "r.csv").exists()
