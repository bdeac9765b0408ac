"""The robot in the CLI (issue 17): --robot, --robot-base, --weld-time, --trajectory, posts.

Bad robot options fail in one line naming the option, before any planning.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest
import trimesh

from tests.cli_helpers import one_line_error, run_cli
from tests.conftest import require_shared
from tests.output_check import csv_rows
from tests.route_fixtures import write_box_station


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
        (["--floor-z", "nan"], "--floor-z"),
    ],
)
def test_bad_robot_options_are_one_line_errors(tmp_path, capsys, extra, needle):
    _, mesh, joints = write_box_station(tmp_path)
    argv = ["plan", str(mesh), str(joints), "-o", str(tmp_path / "r.csv"), "--quiet",
            "--tool", str(_gun_urdf()), "--robot", str(_robot_urdf()), *extra]  # fmt: skip
    assert run_cli(argv) == 2
    assert needle in one_line_error(capsys)
    assert not (tmp_path / "r.csv").exists()


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--trajectory", "t.csv"], "--trajectory needs --robot"),
        (["--robot-base", "0,0,0,0"], "--robot-base needs --robot"),
        (["--floor-z", "0"], "--floor-z needs --robot"),
        (["--robot", "ROBOT"], "--robot needs a --tool"),
    ],
)
def test_robot_options_need_their_companions(tmp_path, capsys, extra, needle):
    _, mesh, joints = write_box_station(tmp_path)
    extra = [str(_robot_urdf()) if e == "ROBOT" else e for e in extra]
    argv = ["plan", str(mesh), str(joints), "-o", str(tmp_path / "r.csv"), "--quiet", *extra]
    assert run_cli(argv) == 2
    assert needle in one_line_error(capsys)


#: a straight arc torch as a URDF tool: root = the robot's mount frame (x out of the flange),
#: TCP 425 mm out along it, TCP +z = root +x; 3 kg at 200 mm
TORCH_URDF = """<?xml version="1.0"?>
<robot name="test_torch">
  <link name="root">
    <inertial><origin xyz="0.2 0 0"/><mass value="3.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><mesh filename="torch.stl"/></geometry></collision>
  </link>
  <link name="tcp"/>
  <joint name="tcp" type="fixed">
    <parent link="root"/><child link="tcp"/><origin xyz="0.425 0 0" rpy="0 1.5707963267948966 0"/>
  </joint>
</robot>
"""


def _torch_urdf(folder):
    from scipy.spatial.transform import Rotation

    from weldplan.tool import arc_torch

    t = arc_torch(bend_angle=0.0, stickout=3.0)
    R = Rotation.from_euler("y", 90, degrees=True).as_matrix()
    v = (np.asarray(t.vertices) @ R.T + [425.0, 0.0, 0.0]) / 1000.0  # metres, root frame
    trimesh.Trimesh(v, np.asarray(t.faces), process=False).export(folder / "torch.stl")
    (folder / "torch.urdf").write_text(TORCH_URDF)
    return folder / "torch.urdf"


@pytest.fixture(scope="module")
def robot_run(tmp_path_factory):
    """``plan`` of the box station with the torch on the KUKA, KRL post and trajectory."""
    tmp = tmp_path_factory.mktemp("robotcli")
    _, mesh, joints = write_box_station(tmp)
    argv = [
        "plan", str(mesh), str(joints), "--margin", "50", "--quiet", "-o", str(tmp / "r.csv"),
        "--tool", str(_torch_urdf(tmp)), "--robot", str(_robot_urdf()),
        "--robot-base=-1800,0,-700,0", "--weld-time", "0.4", "--post", "krl",
        "--trajectory", str(tmp / "traj.csv"), "--json", str(tmp / "r.json"),
        "--tool-csv", str(tmp / "tool.csv"),
    ]  # fmt: skip
    return tmp, run_cli(argv)


def test_every_file_says_what_produced_it_and_what_was_verified(robot_run):
    """Issue 28, item 4: each output starts with the same comment lines (the JSON: its
    "producer" entry) naming weldplan's version, the station and the re-checks that passed; no
    command line, no path, no time; the readers skip them (the other tests here read them)."""
    import json

    import weldplan
    from tests.output_check import comments

    tmp, rc = robot_run
    assert rc == 0
    prod = json.loads((tmp / "r.json").read_text())["producer"]
    assert prod["weldplan"] == weldplan.__version__ and prod["station"] == "r"
    kinds = [c.split(":")[0] for c in prod["verified"]]
    assert kinds == ["route", "tool poses", "tool transitions", "robot"]
    head = [f"produced by weldplan {weldplan.__version__} for station 'r'"]
    head += [f"verified: {c}" for c in prod["verified"]]
    for name in ("r.csv", "tool.csv", "traj.csv"):
        assert comments((tmp / name).read_text())[: len(head)] == head, name
    for name in ("r.src", "r.dat"):
        got = comments((tmp / name).read_text(), ";")
        assert got[1 : len(head) + 1] == head, name  # after "Generated by weldplan for ..."
        assert got[len(head) + 1].startswith("verified: program: every target re-solved by FK")
    text = "\n".join(head)
    assert str(tmp) not in text and "--" not in text and " s " not in text


def test_verify_robot_exits_3_when_the_program_leaves_a_weld_out(robot_run, tmp_path, capsys):
    """verify finds the welds the program leaves out from the joint rows themselves (no exact
    row on the weld's row), not from the statuses the route claims."""
    import json

    tmp, rc = robot_run
    assert rc == 0
    verify = [str(tmp / "box.stl"), "--tool", str(tmp / "torch.urdf"),
              "--robot", str(_robot_urdf())]  # fmt: skip
    assert run_cli(["verify", str(tmp / "r.json"), *verify]) == 0
    assert "not in the program" not in capsys.readouterr().out
    d = json.loads((tmp / "r.json").read_text())
    rob = d["tool"]["robot"]
    assert all(s == "ok" for s in rob["status"]) and len(rob["weld_ids"]) == 4
    # the second weld's exact row made a pass: the same joint path, without that weld
    r = rob["row"][rob["weld_index"][1]]
    rob["exact"] = [e and row != r for e, row in zip(rob["exact"], rob["row"], strict=True)]
    (tmp_path / "r.json").write_text(json.dumps(d))
    assert run_cli(["verify", str(tmp_path / "r.json"), *verify]) == 3
    out = capsys.readouterr().out
    assert f"1 weld(s) not in the program: {rob['weld_ids'][1]}" in out


def test_plan_with_robot_writes_krl_src_dat_and_trajectory_that_replay(robot_run):
    from weldplan.io.posts.parse import parse_krl
    from weldplan.robot import load_robot
    from weldplan.robot.placement import parse_base

    tmp, rc = robot_run
    assert rc == 0
    src, dat = (tmp / "r.src").read_text(), (tmp / "r.dat").read_text()
    prog = parse_krl(src, dat)
    assert prog.load_mass == pytest.approx(3.0)
    assert len(prog.welds) == 4 and all("WAIT SEC 0.400" in w for _, w in prog.welds)
    rows = [r for r in csv.reader((tmp / "traj.csv").open()) if not r[0].startswith("#")]
    robot = load_robot(_robot_urdf(), base=parse_base("-1800,0,-700,0"))
    assert rows[0] == ["t", "step", *robot.joint_names]
    data = np.array([[float(v) for v in r] for r in rows[1:]])
    assert np.all(np.diff(data[:, 0]) >= 0)
    # every weld point of the program is a pose of the trajectory: FK of some CSV row puts the
    # flange where the program's E6POS (in BASE, with TOOL) puts it
    T_fk = np.linalg.solve(robot.base, robot.fk(data[:, 2:]))
    route = csv_rows(tmp / "r.csv")
    for _, name, _, _ in [m for m in prog.moves][1:-1]:
        T_prog = prog.base @ prog.points[name][0] @ np.linalg.inv(prog.tool)
        d = np.linalg.norm(T_fk[:, :3, 3] - T_prog[:3, 3], axis=1)
        assert d.min() <= 0.01
    welds = [r for r in route if r["kind"] == "weld"]
    assert len(welds) == 4


def test_plan_with_robot_refuses_a_base_that_reaches_nothing(tmp_path, capsys):
    _, mesh, joints = write_box_station(tmp_path)
    argv = [
        "plan", str(mesh), str(joints), "--margin", "50", "--quiet", "-o", str(tmp_path / "r.csv"),
        "--tool", str(_torch_urdf(tmp_path)), "--robot", str(_robot_urdf()),
        "--robot-base=-9000,0,0,0", "--trajectory", str(tmp_path / "t.csv"),
    ]  # fmt: skip
    assert run_cli(argv) == 2  # bad input: the base, named as the field
    line = one_line_error(capsys)
    assert "reaches none" in line and "--robot-base" in line
    assert not (tmp_path / "r.csv").exists() and not (tmp_path / "t.csv").exists()


@pytest.mark.slow
def test_plan_with_robot_that_serves_no_weld_is_one_line_naming_the_cause(tmp_path, capsys):
    """car2's 50-spot station with the shared gun: 9 spots have a gun pose, and from the
    searched base every usable branch of each puts link_3 in the body. The run says so in one
    line (the base, the statuses, the first weld's cause) and writes nothing."""
    from pathlib import Path

    body = require_shared("bodies", "car2.obj")
    joints = Path(__file__).resolve().parents[2] / "assets" / "car2" / "car2_synthetic_50.csv"
    argv = [
        "plan", str(body), str(joints), "--length", "4500", "--quiet",
        "-o", str(tmp_path / "r.csv"), "--tool", str(_gun_urdf()), "--tcp", "nozzle_tip",
        "--robot", str(_robot_urdf()), "--post", "krl",
    ]  # fmt: skip
    assert run_cli(argv) == 1
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("WARNING")]
    assert len(lines) == 1, err  # the station column's warning aside
    line = lines[0]
    assert "serves none of the 9 weld(s)" in line and "from its base (" in line
    assert "collision (first weld" in line and "link_3" in line
    assert not list(tmp_path.iterdir())
