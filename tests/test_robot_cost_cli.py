"""``--cost time`` and mesh tools on robots in the CLI (issue 17): runs and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.cli_helpers import one_line_error, run_cli
from tests.route_fixtures import write_box_station
from tests.test_robot_cli import _robot_urdf, _torch_urdf

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


def test_cost_time_run_states_its_bound_in_seconds(tmp_path):
    _, mesh, joints = write_box_station(tmp_path)
    argv = ["plan", str(mesh), str(joints), "--margin", "50", "--quiet",
            "-o", str(tmp_path / "r.csv"), "--json", str(tmp_path / "r.json"),
            "--tool", str(_torch_urdf(tmp_path)), "--robot", str(_robot_urdf()), BASE,
            "--weld-time", "0.4", "--cost", "time",
            "--trajectory", str(tmp_path / "t.csv")]  # fmt: skip
    assert run_cli(argv) == 0
    d = json.loads((tmp_path / "r.json").read_text())
    st = d["stats"]["cost_time"]
    assert st["cost"] == "time" and st["weld_time"] == 0.4
    assert 4 * 0.4 <= st["time_bound"] <= st["time_cost"]
    t_end = float((tmp_path / "t.csv").read_text().splitlines()[-1].split(",")[0])
    assert st["time_bound"] <= t_end  # the proved bound is below the timed cycle


def test_a_mesh_tool_works_with_the_robot_like_its_urdf(tmp_path):
    from weldplan.io.posts.parse import parse_krl

    _, mesh, joints = write_box_station(tmp_path)
    stl, tcp = _torch_mesh(tmp_path)
    out = {}
    for name, tool in (("mesh", ["--tool", str(stl), "--tcp", tcp, "--tool-mass", "3"]),
                       ("urdf", ["--tool", str(_torch_urdf(tmp_path))])):  # fmt: skip
        argv = ["plan", str(mesh), str(joints), "--margin", "50", "--quiet",
                "-o", str(tmp_path / f"{name}.csv"), *tool, "--robot", str(_robot_urdf()), BASE,
                "--post", "krl"]  # fmt: skip
        assert run_cli(argv) == 0, name
        src, dat = (tmp_path / f"{name}.src").read_text(), (tmp_path / f"{name}.dat").read_text()
        out[name] = parse_krl(src, dat)
    assert out["mesh"].load_mass == pytest.approx(3.0)
    np.testing.assert_allclose(out["mesh"].tool, out["urdf"].tool, atol=1e-6)
