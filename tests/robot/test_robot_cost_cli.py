"""``--cost time`` and mesh tools on robots in the CLI (issue 17): runs and one-line errors."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from tests.cli_helpers import one_line_error, run_cli
from tests.output_check import trajectory_q
from tests.robot.test_robot_cli import _robot_urdf, _torch_urdf
from tests.route_fixtures import write_box_station

BASE = "--robot-base=-1800,0,-700,0"


def _torch_mesh(folder):
    """The test torch of test_robot_cli as a mesh in mm, in its mounting frame, with the TCP
    that URDF gives it (425 mm along x, TCP +z = mount +x)."""
    import trimesh
    from scipy.spatial.transform import Rotation

    from weldplan.tool import arc_torch

    t = arc_torch(bend_angle=0.0, stickout=3.0)
    R = Rotation.from_euler("y", 90, degrees=True).as_matrix()
    v = np.asarray(t.vertices) @ R.T + [425.0, 0.0, 0.0]
    trimesh.Trimesh(v, np.asarray(t.faces), process=False).export(folder / "torch_mm.stl")
    return folder / "torch_mm.stl", "425,0,0,0,90,0"


def test_cost_time_needs_a_robot(tmp_path, capsys):
    _, mesh, joints = write_box_station(tmp_path)
    argv = ["plan", str(mesh), str(joints), "-o", str(tmp_path / "r.csv"), "--quiet",
            "--cost", "time"]  # fmt: skip
    assert run_cli(argv) == 2
    assert "--cost time needs --robot" in one_line_error(capsys)


def test_a_mesh_tool_on_a_robot_needs_its_mass(tmp_path, capsys):
    _, mesh, joints = write_box_station(tmp_path)
    stl, tcp = _torch_mesh(tmp_path)
    argv = ["plan", str(mesh), str(joints), "-o", str(tmp_path / "r.csv"), "--quiet",
            "--tool", str(stl), "--tcp", tcp, "--robot", str(_robot_urdf()), BASE]  # fmt: skip
    assert run_cli(argv) == 2
    line = one_line_error(capsys)
    assert "--tool-mass" in line and "torch_mm.stl" in line
    assert not (tmp_path / "r.csv").exists()


@pytest.fixture(scope="module")
def time_run(tmp_path_factory):
    """``plan --cost time`` of the box station with the torch on the KUKA, JSON and trajectory."""
    tmp = tmp_path_factory.mktemp("costtime")
    _, mesh, joints = write_box_station(tmp)
    torch = _torch_urdf(tmp)
    argv = ["plan", str(mesh), str(joints), "--margin", "50", "--quiet",
            "-o", str(tmp / "r.csv"), "--json", str(tmp / "r.json"),
            "--tool", str(torch), "--robot", str(_robot_urdf()), BASE,
            "--weld-time", "0.4", "--cost", "time",
            "--trajectory", str(tmp / "t.csv")]  # fmt: skip
    return tmp, mesh, torch, run_cli(argv)


def test_cost_time_run_states_its_bound_in_seconds(time_run):
    tmp, _, _, rc = time_run
    assert rc == 0
    d = json.loads((tmp / "r.json").read_text())
    st = d["stats"]["cost_time"]
    assert st["cost"] == "time" and st["weld_time"] == 0.4
    assert 4 * 0.4 <= st["time_bound"] <= st["time_cost"]
    t_end = float((tmp / "t.csv").read_text().splitlines()[-1].split(",")[0])
    assert st["time_bound"] <= t_end  # the proved bound is below the timed cycle


def test_the_robot_route_round_trips_through_the_route_json(time_run):
    from weldplan.io.export import read_route
    from weldplan.robot.program import robot_route_of
    from weldplan.weld.route import Route

    tmp, _, _, rc = time_run
    assert rc == 0
    route = read_route(tmp / "r.json")
    rr = robot_route_of(route)
    d = json.loads((tmp / "r.json").read_text())["tool"]["robot"]
    # the robot follows the tool stage's order and transitions: its rows are that route's
    followed = Route.from_dict(d["follows"]["route"])
    assert rr.weld_ids == followed.order == tuple(d["follows"]["route"]["order"])
    assert sorted(rr.weld_ids) == sorted(route.order) and len(rr.status) == 4
    assert rr.q.shape == (len(rr.row), 6) and rr.row.max() < len(followed.waypoints())
    assert d["weld_branch"] == rr.weld_branch.tolist()
    np.testing.assert_array_equal(rr.q, np.asarray(d["q"]))
    # the trajectory replays the same joint route: its first row is the route's first row
    first = trajectory_q(tmp / "t.csv")[0]
    np.testing.assert_allclose(first, rr.q[0], atol=1e-6)  # the CSV keeps 1e-8 rad


def test_verify_rechecks_the_robot_route_by_fk_and_collision(time_run, capsys):
    tmp, mesh, torch, rc = time_run
    assert rc == 0
    argv = ["verify", str(tmp / "r.json"), str(mesh), "--tool", str(torch)]
    assert run_cli(argv) == 0
    assert "robot route ok" in capsys.readouterr().out
    for joint, needle in ((5, "deg"), (0, "mm")):
        d = json.loads((tmp / "r.json").read_text())
        k = d["tool"]["robot"]["weld_index"][1]
        d["tool"]["robot"]["q"][k][joint] += 0.01  # A6 turns the torch about its axis, A1 moves it
        (tmp / "bad.json").write_text(json.dumps(d))
        argv[1] = str(tmp / "bad.json")
        assert run_cli(argv) == 1
        line = one_line_error(capsys)
        assert "robot route: FK misses the route" in line
        miss = line.split("misses the route by ")[1]
        assert float(miss.split(" mm, ")[0 if needle == "mm" else 1].split()[0]) > 0.01


def test_the_summary_says_which_order_the_robot_follows_and_why(time_run):
    from weldplan.commands._robot import _order_rows
    from weldplan.io.export import read_route
    from weldplan.robot.program import robot_route_of
    from weldplan.robot.route import gun_route
    from weldplan.tool.poses import route_poses, route_tool_path

    tmp, _, _, rc = time_run
    assert rc == 0
    route = read_route(tmp / "r.json")
    rr = robot_route_of(route)
    gun = gun_route(route, route_poses(route), route_tool_path(route), contact_radius=20.0)
    rows = dict(_order_rows(route, gun, rr))
    order = "-".join(rr.weld_ids)
    assert rows["robot order"].startswith(f"{order}: the tool stage's order")
    if rr.weld_ids != route.order:  # then the row says so, and why
        assert f"not the point-tip route's ({'-'.join(route.order)})" in rows["robot order"]
    n_legs = sum(s == "ok" for s in rr.status) - 1
    m = re.match(r"(\d+) along .*?(\d+) detoured .*?(\d+) by one joint", rows["robot legs"])
    assert m is not None and sum(int(g) for g in m.groups()) == n_legs
