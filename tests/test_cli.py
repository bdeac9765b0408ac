"""The command line: plan, demo, verify, view; one-line user errors (exit 2); failed runs
leave existing output files untouched; verification failures refuse to write (exit 1)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.cli_helpers import run_cli
from tests.output_check import csv_rows
from tests.route_fixtures import BOX_JOINTS_CSV, write_box_station
from weldplan.cli import main
from weldplan.weld import verify as verify_mod
from weldplan.weld.verify import VerifyReport, Violation

#: the box scene of tests/route_fixtures with joints on the floor on both sides of the wall
JOINTS_CSV = BOX_JOINTS_CSV


def _needs_planner():
    pytest.importorskip("weldplan.weld.local")
    pytest.importorskip("weldplan.optim.discrete.sequence")


@pytest.fixture
def files(tmp_path):
    return write_box_station(tmp_path)


def _one_line_error(capsys, rc_expected=2):
    err = capsys.readouterr().err
    # log warnings said before the error (an old route without provenance, ...) are not the error
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("WARNING weldplan")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("cmd", ["plan", "demo", "verify", "view", "bench"])
def test_help_for_every_command(cmd, capsys):
    with pytest.raises(SystemExit) as e:
        main([cmd, "--help"])
    assert e.value.code == 0
    assert "usage: weldplan " + cmd in capsys.readouterr().out


def test_usage_errors_are_one_line(capsys):
    for argv in (["plan"], ["plan", "a.stl", "j.csv"], ["nope"], ["plan", "--planner", "x"]):
        with pytest.raises(SystemExit) as e:
            main(argv)
        assert e.value.code == 2
        assert _one_line_error(capsys).startswith("weldplan")


def test_user_errors_exit_2_with_one_line(files, capsys):
    tmp, mesh, joints = files
    bad = tmp / "bad.csv"
    bad.write_text("id,x,y,z\nA,1,2,zz\n")
    cases = {
        "missing mesh": (
            ["plan", str(tmp / "nope.stl"), str(joints), "-o", str(tmp / "r.csv")],
            "nope.stl",
        ),
        "bad joints": (["plan", str(mesh), str(bad), "-o", str(tmp / "r.csv")], "line 2"),
        "no folder": (
            ["plan", str(mesh), str(joints), "-o", str(tmp / "no" / "r.csv")],
            "does not exist",
        ),
        "clearance": (
            ["plan", str(mesh), str(joints), "-o", str(tmp / "r.csv"), "--clearance", "-1"],
            "clearance",
        ),
        "post file": (
            [
                "plan",
                str(mesh),
                str(joints),
                "-o",
                str(tmp / "r.csv"),
                "--post-file",
                str(tmp / "x.mod"),
            ],
            "--post",
        ),
        "same file": (
            [
                "plan",
                str(mesh),
                str(joints),
                "-o",
                str(tmp / "r.csv"),
                "--json",
                str(tmp / "r.csv"),
            ],
            "given for both",
        ),
        "bad route": (["verify", str(bad), str(mesh)], "not valid JSON"),
        "route missing": (["verify", str(tmp / "none.json"), str(mesh)], "none.json"),
        "aco": (["demo", "--aco", "0", "-o", str(tmp / "r.csv")], "--aco"),
    }
    for name, (argv, needle) in cases.items():
        assert run_cli(argv) == 2, name
        line = _one_line_error(capsys)
        assert needle in line, (name, line)


def test_failed_run_leaves_existing_outputs_untouched(files, capsys):
    tmp, mesh, joints = files
    out = tmp / "route.csv"
    out.write_text("a good route\n")
    bad = tmp / "bad.csv"
    bad.write_text("id,x,y\nA,1,2\n")
    assert main(["plan", str(mesh), str(bad), "-o", str(out), "--quiet"]) == 2
    assert out.read_text() == "a good route\n"
    assert sorted(p.name for p in tmp.iterdir()) == [
        "bad.csv",
        "box.stl",
        "joints.csv",
        "route.csv",
    ]


def test_plan_writes_every_output_and_verifies(files, capsys):
    _needs_planner()
    tmp, mesh, joints = files
    out = tmp / "route.csv"
    argv = [
        "plan",
        str(mesh),
        str(joints),
        "-o",
        str(out),
        "--json",
        str(tmp / "r.json"),
        "--html",
        str(tmp / "r.html"),
        "--post",
        "krl",
        "--margin",
        "40",
    ]
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert cap.err == ""  # not a terminal: no progress bars
    for key in ("joints", "pairs planned", "route length", "lower bound", "gap", "time"):
        assert key in cap.out
    rows = csv_rows(out)
    assert sorted(r["joint_id"] for r in rows if r["kind"] == "weld") == ["A", "B", "C", "D"]
    assert (tmp / "route.src").read_text().startswith("DEF route()")  # the station's name
    assert (tmp / "r.html").stat().st_size > 100_000
    # the saved route verifies again from the files alone
    assert main(["verify", str(tmp / "r.json"), str(mesh), "--joints", str(joints)]) == 0
    assert "route ok" in capsys.readouterr().out
    # --quiet prints nothing at all
    assert main([*argv, "--quiet"]) == 0
    assert capsys.readouterr() == ("", "")


def test_plan_refuses_a_route_that_fails_verification(files, capsys, monkeypatch):
    _needs_planner()
    tmp, mesh, joints = files
    out = tmp / "route.csv"
    out.write_text("a good route\n")

    def failing(route, part, **kw):
        v = Violation("collision", "the segment hits the part at 5 mm clearance", 2, 1, "C", "B")
        return VerifyReport(False, (v,), 5.0, 3, 4, 3)

    monkeypatch.setattr(verify_mod, "verify_route", failing)
    rc = main(
        [
            "plan",
            str(mesh),
            str(joints),
            "-o",
            str(out),
            "--html",
            str(tmp / "r.html"),
            "--margin",
            "40",
        ]
    )
    assert rc == 1
    line = _one_line_error(capsys)
    assert "leg 2 (C -> B), segment 1" in line and "nothing written" in line
    assert out.read_text() == "a good route\n"
    assert not (tmp / "r.html").exists()


def test_verify_command_catches_a_tampered_route(files, capsys):
    from tests.route_fixtures import box_route

    tmp, mesh, _ = files
    good = tmp / "good.json"
    good.write_text(box_route().to_json())
    assert main(["verify", str(good), str(mesh)]) == 0
    d = json.loads(box_route().to_json())
    d["legs"][1]["points"][2] = [0.0, 30.0, 10.0]  # through the wall
    bad = tmp / "bad.json"
    bad.write_text(json.dumps(d))
    capsys.readouterr()
    assert main(["verify", str(bad), str(mesh)]) == 1
    line = _one_line_error(capsys)
    assert "leg 1 (C -> B), segment 1" in line


def test_view_writes_a_static_page(files, capsys):
    from tests.route_fixtures import box_route

    tmp, mesh, _ = files
    r = tmp / "r.json"
    r.write_text(box_route().to_json())
    assert main(["view", str(r), str(mesh), "--html", str(tmp / "v.html")]) == 0
    assert (tmp / "v.html").read_text().startswith("<!DOCTYPE html>")


@pytest.mark.slow
def test_demo_plans_verifies_and_exports(tmp_path, monkeypatch, capsys):
    _needs_planner()
    monkeypatch.chdir(tmp_path)
    assert main(["demo", "--json", "route.json"]) == 0
    out = capsys.readouterr().out
    assert "route ok" in out and "595.10" in out
    rows = csv_rows(tmp_path / "route.csv")
    welds = [r for r in rows if r["kind"] == "weld"]
    assert sorted(int(r["joint_id"]) for r in welds) == list(range(1, 16))
    # the demo joints carry approach directions: exported on weld rows
    assert all(r["tool_x"] != "" for r in welds)
    assert (tmp_path / "route.html").stat().st_size > 100_000
    from weldplan.io.export import read_route

    route = read_route(tmp_path / "route.json")
    assert np.isclose(route.lower_bound, 595.10, atol=0.01)


def test_progress_bars_draw_on_a_terminal_only():
    import io

    from weldplan.commands._progress import ProgressBars

    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty, pipe = Tty(), io.StringIO()
    for stream in (tty, pipe):
        bars = ProgressBars(stream=stream)
        for d in range(4):
            bars("local", d, 3 if d < 4 else 3)
        with bars.stage("verify"):
            pass
        bars.close()
    assert pipe.getvalue() == ""
    text = tty.getvalue()
    assert "local paths" in text and "3/3" in text and "verifying" in text
    assert ProgressBars(enabled=False, stream=tty).enabled is False


def test_a_station_s_progress_names_the_robot_and_its_stage_in_words():
    """A station's shares report ``"robot2 local"`` (weldplan.multi.shares): the bar says
    ``robot 2: local paths``, and a stage it has no words for keeps its name."""
    import io

    from weldplan.commands._progress import ProgressBars, label

    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty = Tty()
    bars = ProgressBars(stream=tty)
    bars("robot2 local", 1, 3)
    bars("robot12 poses", 0, 1)
    bars("allocation", 0, 3)
    bars.close()
    text = tty.getvalue()
    assert "robot 2: local paths" in text and "robot 12: gun poses" in text
    assert "robot2" not in text and "allocation" in text
    assert label("robot3 new-stage") == "robot 3: new-stage" and label("odd") == "odd"
