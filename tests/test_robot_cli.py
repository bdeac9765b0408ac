"""The robot in the CLI (issue 17): --robot, --robot-base, --weld-time, --trajectory, posts.

Bad robot options fail in one line naming the option, before any planning.
"""

from __future__ import annotations

import pytest

from tests.conftest import require_shared
from tests.route_fixtures import write_box_station
from weldplan.cli import main


def _rc(argv) -> int:
    try:
        return main(argv)
    except SystemExit as e:
        return int(e.code)


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    return lines[0]


def _robot_urdf():
    return require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")


def _gun_urdf():
    return require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--weld-time", "nan"], "--weld-time"),
        (["--weld-time", "-1"], "--weld-time"),
        (["--acc-scale", "0"], "--acc-scale"),
        (["--robot-base", "1,2,3"], "--robot-base"),
        (["--robot-base", "1,2,3,inf"], "--robot-base"),
    ],
)
def test_bad_robot_options_are_one_line_errors(tmp_path, capsys, extra, needle):
    _, mesh, joints = write_box_station(tmp_path)
    argv = ["plan", str(mesh), str(joints), "-o", str(tmp_path / "r.csv"), "--quiet",
            "--tool", str(_gun_urdf()), "--robot", str(_robot_urdf()), *extra]  # fmt: skip
    assert _rc(argv) == 2
    assert needle in _one_line_error(capsys)
    assert not (tmp_path / "r.csv").exists()


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--trajectory", "t.csv"], "--trajectory needs --robot"),
        (["--robot-base", "0,0,0,0"], "--robot-base needs --robot"),
        (["--robot", "ROBOT"], "--robot needs a URDF --tool"),
    ],
)
def test_robot_options_need_their_companions(tmp_path, capsys, extra, needle):
    _, mesh, joints = write_box_station(tmp_path)
    extra = [str(_robot_urdf()) if e == "ROBOT" else e for e in extra]
    argv = ["plan", str(mesh), str(joints), "-o", str(tmp_path / "r.csv"), "--quiet", *extra]
    assert _rc(argv) == 2
    assert needle in _one_line_error(capsys)
