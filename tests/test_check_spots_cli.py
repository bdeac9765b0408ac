"""``weldplan check-spots`` (issue 29 item 4): exit codes, the table, the JSON and the page, and
one-line errors for bad input, on the demo cell with the shared spot gun and the KR 150."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from tests.cli_helpers import one_line_error, run_cli
from tests.conftest import require_shared
from weldplan.errors import EXIT_INPUT, EXIT_OK, EXIT_PARTIAL
from weldplan.study.result import FeasibilityStudy

ROOT = Path(__file__).resolve().parents[1]
PART = str(ROOT / "assets" / "demo" / "part.stl")
#: three demo spots (for the option errors: they are never studied)
SPOTS = (
    "id,x,y,z,nx,ny,nz\n"
    "1,1443.60,-53.20,686.00,0.0,0.0,1.0\n"
    "9,1474.16,-111.25,791.00,0.0,0.0,1.0\n"
    "13,1554.17,-94.37,909.95,0.0,0.0,1.0\n"
)
#: the robot's base 1 m behind the demo part (the study's searched one, tests/test_study.py)
BASE = "448.1,95.3,652.7,-7.5"


def _gun() -> str:
    return str(require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf"))


def _robot() -> str:
    return str(require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf"))


def _spots_with_directions(tmp: Path, off: bool) -> Path:
    """The three spots with the demo CSV's own directions (and the moved one)."""
    from weldplan.io.joints import read_joints

    demo = read_joints(ROOT / "assets" / "demo" / "joints.csv")
    lines = ["id,x,y,z,nx,ny,nz"]
    for jid in ("1", "9", "13"):
        k = demo.ids.index(jid)
        (x, y, z), (a, b, c) = demo.xyz[k], demo.directions[k]
        lines.append(f"{jid},{x},{y},{z},{a},{b},{c}")
        if off and jid == "1":
            p = demo.xyz[k] + 30.0 * demo.directions[k]
            lines.append(f"off,{p[0]},{p[1]},{p[2]},{a},{b},{c}")
    path = tmp / ("spots_off.csv" if off else "spots.csv")
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def partial(tmp_path_factory):
    """The study of the three spots and the one off the part, robot at BASE, all outputs."""
    tmp = tmp_path_factory.mktemp("checkspots")
    spots = _spots_with_directions(tmp, off=True)
    argv = [
        "check-spots", PART, str(spots), "--tool", _gun(), "--tcp", "nozzle_tip",
        "--robot", _robot(), "--robot-base", BASE, "--quiet",
        "-o", str(tmp / "t.csv"), "--json", str(tmp / "s.json"), "--html", str(tmp / "p.html"),
    ]  # fmt: skip
    return tmp, run_cli(argv)


def test_some_spots_not_feasible_exit_3_with_the_table_json_and_page(partial):
    tmp, rc = partial
    assert rc == EXIT_PARTIAL
    lines = (tmp / "t.csv").read_text().splitlines()
    assert lines[0].startswith("# weldplan check-spots") and "part frame" in lines[0]
    assert lines[1].startswith("# robot kr150r3100_2: base 448.1,95.3,652.7,-7.50 (given)")
    rows = list(csv.DictReader(lines[2:]))
    assert [r["id"] for r in rows] == ["1", "off", "9", "13"]
    by = {r["id"]: r for r in rows}
    gun, rob = "gun:spot_welding_gun", "robot:kr150r3100_2:spot_welding_gun"
    assert by["off"][gun] == "no_surface" and by["off"][rob] == "no_surface"
    assert by["off"]["feasible"] == "no" and "no surface within 5 mm" in by["off"][f"{gun}:reason"]
    assert float(by["off"]["surface_mm"]) == pytest.approx(30.0, abs=0.5)
    study = FeasibilityStudy.from_json((tmp / "s.json").read_text())
    for r in rows:  # the table is the study
        sp = study.spots[study.ids.index(r["id"])]
        assert r[gun] == sp.guns[0].status and r[rob] == sp.robots[0].status
        assert r["feasible"] == ("yes" if sp.feasible else "no")
        assert r["stack"] == sp.stack
    assert study.robots[0].searched is False
    page = (tmp / "p.html").read_text()
    assert "no surface near the spot: 1" in page and "weld feasibility study" in page
    assert f"feasible: a robot reaches a free gun pose: {int(study.feasible.sum())}" in page


def test_every_spot_feasible_exits_0(tmp_path):
    spots = _spots_with_directions(tmp_path, off=False)
    argv = [
        "check-spots", PART, str(spots), "--tool", _gun(), "--tcp", "nozzle_tip", "--quiet",
        "-o", str(tmp_path / "t.csv"), "--json", str(tmp_path / "s.json"),
    ]  # fmt: skip
    assert run_cli(argv) == EXIT_OK
    study = json.loads((tmp_path / "s.json").read_text())
    assert [s["guns"][0]["status"] for s in study["spots"]] == ["ok"] * 3
    assert study["robots"] == []


def test_a_part_pose_studies_in_the_cell_frame_what_the_part_frame_gives(partial, tmp_path):
    """``--part-pose`` (moved and lifted, not turned) with the base and the floor in the cell
    frame: the same verdicts as the part-frame run of ``partial``, every position moved by the
    pose, the table and the JSON saying "cell"."""
    import numpy as np

    part_tmp, _ = partial
    spots = _spots_with_directions(tmp_path, off=True)
    argv = [
        "check-spots", PART, str(spots), "--tool", _gun(), "--tcp", "nozzle_tip",
        "--robot", _robot(), "--robot-base=1048.1,-304.7,500,-7.5", "--quiet",
        "--part-pose=600,-400,-152.7,0,0,0", "--floor-z", "0",
        "-o", str(tmp_path / "t.csv"), "--json", str(tmp_path / "s.json"),
    ]  # fmt: skip
    assert run_cli(argv) == EXIT_PARTIAL
    assert "cell frame" in (tmp_path / "t.csv").read_text().splitlines()[0]
    cell = FeasibilityStudy.from_json((tmp_path / "s.json").read_text())
    part = FeasibilityStudy.from_json((part_tmp / "s.json").read_text())
    assert cell.frame == "cell" and part.frame == "part"
    for c, p in zip(cell.spots, part.spots, strict=True):
        assert c.id == p.id and c.feasible == p.feasible
        assert [g.status for g in c.guns] == [g.status for g in p.guns]
        assert [r.status for r in c.robots] == [r.status for r in p.robots]
        assert np.allclose(c.position, np.add(p.position, (600.0, -400.0, -152.7)), atol=1e-6)
    assert np.allclose(cell.robots[0].xyz_yaw(), (1048.1, -304.7, 500.0, -7.5))


@pytest.mark.parametrize("value", ["oops", "nan", "inf"])
def test_a_bad_spot_line_is_one_line_naming_file_line_and_field(tmp_path, capsys, value):
    bad = tmp_path / "bad.csv"
    bad.write_text(f"id,x,y,z\n1,1443.6,-53.2,686\n2,1399.5,{value},688.4\n")
    argv = ["check-spots", PART, str(bad), "--tool", _gun(), "-o", str(tmp_path / "t.csv")]
    assert run_cli(argv) == EXIT_INPUT
    line = one_line_error(capsys)
    assert "bad.csv" in line and "line 3" in line and "'y'" in line
    assert not (tmp_path / "t.csv").exists()


def test_two_tools_get_their_own_columns(tmp_path):
    """The shared gun (a URDF, its TCP joint) beside an arc torch given as a mesh with --tcp:
    each a verdict per spot under its file's stem."""
    from weldplan.tool import arc_torch

    arc_torch(bend_angle=0.0).mesh.export(tmp_path / "torch.stl")
    spots = _spots_with_directions(tmp_path, off=False)
    argv = [
        "check-spots", PART, str(spots), "--quiet", "-o", str(tmp_path / "t.csv"),
        "--tool", _gun(), "--tcp", "nozzle_tip", "--tool", str(tmp_path / "torch.stl"),
        "--tcp", "0,0,0,0,0,0", "--json", str(tmp_path / "s.json"),
    ]  # fmt: skip
    rc = run_cli(argv)
    study = FeasibilityStudy.from_json((tmp_path / "s.json").read_text())
    assert study.tools == ("spot_welding_gun", "torch")
    assert rc == (EXIT_OK if study.all_feasible else EXIT_PARTIAL)
    rows = list(csv.DictReader((tmp_path / "t.csv").read_text().splitlines()[1:]))
    for r, sp in zip(rows, study.spots, strict=True):
        assert r["gun:torch"] == sp.guns[1].status
        assert r["gun:spot_welding_gun"] == sp.guns[0].status == "ok"
        assert r["feasible"] == ("yes" if sp.feasible else "no")


def test_the_built_in_arc_torch_is_studied_as_a_station_mounts_it(tmp_path, capsys):
    """``--tool builtin:arc_torch,bend_angle=0`` (a station's ``tool.builtin``): its column
    named by the builtin, each verdict the one of the study run in Python on the tool a
    station's ``[robot.tool] builtin = "arc_torch"`` mounts; ``--tcp`` with it is refused."""
    from weldplan.io.joints import read_joints
    from weldplan.io.mesh import load_part
    from weldplan.station.model import ToolSpec
    from weldplan.station.mount import mount_tool
    from weldplan.study import StudyTool, check_spots

    spots = _spots_with_directions(tmp_path, off=False)
    torch = "builtin:arc_torch,bend_angle=0"
    argv = ["check-spots", PART, str(spots), "--quiet", "-o", str(tmp_path / "t.csv"),
            "--tool", torch, "--json", str(tmp_path / "s.json")]  # fmt: skip
    rc = run_cli(argv)
    study = FeasibilityStudy.from_json((tmp_path / "s.json").read_text())
    assert study.tools == ("arc_torch",)
    assert rc == (EXIT_OK if study.all_feasible else EXIT_PARTIAL)
    spec = ToolSpec(builtin="arc_torch", params={"bend_angle": 0.0})
    tool = StudyTool("arc_torch", mount_tool(spec).tool, spec)
    live = check_spots(load_part(PART), read_joints(spots), [tool], [])
    assert [s.guns[0].status for s in study.spots] == [s.guns[0].status for s in live.spots]
    rows = list(csv.DictReader((tmp_path / "t.csv").read_text().splitlines()[1:]))
    assert [r["gun:arc_torch"] for r in rows] == [s.guns[0].status for s in live.spots]
    bad = [*argv[:-2], "--tcp", "0,0,0,0,0,0", "-o", str(tmp_path / "u.csv")]
    assert run_cli(bad) == EXIT_INPUT
    assert "the built-in tool carries its own TCP" in one_line_error(capsys)
    assert run_cli([*argv[:-4], "--tool", "builtin:arc_torch,reach=3"]) == EXIT_INPUT
    assert "reach" in one_line_error(capsys)


def test_mismatched_options_are_one_line_errors(tmp_path, capsys):
    spots = tmp_path / "s.csv"
    spots.write_text(SPOTS)
    out = ["-o", str(tmp_path / "t.csv")]
    argv = ["check-spots", PART, str(spots), "--tool", _gun(), "--tool", _gun()]
    assert run_cli([*argv, "--tcp", "a", "--tcp", "b", "--tcp", "c", *out]) == EXIT_INPUT
    assert "--tcp once, or once per --tool (2), got 3" in one_line_error(capsys)
    assert run_cli([*argv[:5], "--robot-base", BASE, *out]) == EXIT_INPUT
    assert "--robot-base, --opw and --floor-z need --robot" in one_line_error(capsys)
    bad_base = [*argv[:5], "--robot", _robot(), "--robot-base", "1,2,3", *out]
    assert run_cli(bad_base) == EXIT_INPUT
    assert "x,y,z,yaw" in one_line_error(capsys)
    assert not (tmp_path / "t.csv").exists()


@pytest.mark.slow
def test_a_searched_base_is_said_in_the_table_and_the_json(tmp_path):
    spots = _spots_with_directions(tmp_path, off=False)
    argv = [
        "check-spots", PART, str(spots), "--tool", _gun(), "--tcp", "nozzle_tip", "--quiet",
        "--robot", _robot(), "-o", str(tmp_path / "t.csv"), "--json", str(tmp_path / "s.json"),
    ]  # fmt: skip
    rc = run_cli(argv)
    study = FeasibilityStudy.from_json((tmp_path / "s.json").read_text())
    assert study.robots[0].searched and study.robots[0].tool == "spot_welding_gun"
    assert rc == (EXIT_OK if study.all_feasible else EXIT_PARTIAL)
    assert "(searched for tool spot_welding_gun)" in (tmp_path / "t.csv").read_text()
    assert study.reach_matrix().shape == (3, 1)


def test_help_says_the_exit_codes(capsys):
    assert run_cli(["check-spots", "--help"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "usage: weldplan check-spots" in out and "3  some spots are not feasible" in out


@pytest.mark.slow
def test_headless_chromium_draws_the_spots_in_their_verdicts_colours(partial, tmp_path):
    """The page (fixture: three spots feasible or not, one grey off the part) shows the legend's
    colours in the 3D view: grey for the spot off the part, green for the feasible ones."""
    pytest.importorskip("PIL")
    import numpy as np
    from PIL import Image

    from tests.test_viewer import _chromium, _run_chromium

    assert _chromium()
    tmp, _ = partial
    png = tmp_path / "p.png"
    shot = _run_chromium(tmp_path, f"--screenshot={png}", (tmp / "p.html").resolve().as_uri())
    assert shot.returncode == 0 and png.exists(), shot.stderr[-2000:]
    img = np.asarray(Image.open(png).convert("RGB"), dtype=int)
    view = img[200:, 450:]  # below and right of the legend box
    r, g, b = (view[..., k] for k in range(3))
    green = (g > r + 60) & (g > b + 30)  # 0x2CA02C lit
    assert green.sum() > 10
    assert len(np.unique(view.reshape(-1, 3), axis=0)) > 50  # not a blank page
