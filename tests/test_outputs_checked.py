"""Outputs that cannot mislead (issue 28, item 4): every pose in every CSV a run writes is
re-checked here with python-fcl on the meshes (:mod:`tests.output_check`, none of weldplan's
checkers) and none puts the tool inside the part; the trajectory's times strictly increase."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest
import trimesh

from tests.cli_helpers import run_cli
from tests.conftest import ROOT, require_shared
from tests.output_check import InsideCheck, csv_poses, trajectory_q, trajectory_t
from tests.route_fixtures import write_box_station
from weldplan.io.joints import read_joints
from weldplan.station.model import ToolSpec
from weldplan.station.mount import load_tool_spec

#: the station's contact radius (mm, ``[tool_settings] contact_radius``'s default)
CONTACT_MM = 20.0


def _checker(mesh: Path, joints: Path, tool) -> InsideCheck:
    part = trimesh.load(mesh, force="mesh")
    spots = read_joints(joints).xyz
    return InsideCheck(part.vertices, part.faces, tool.vertices, tool.faces, spots, CONTACT_MM)


def _route_rows_with_a_pose(path: Path) -> list[str]:
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    return [r["kind"] for r in csv.DictReader(lines) if r["qw"]]


def test_box_station_with_the_arc_torch_writes_no_pose_inside_the_part(tmp_path):
    tmp, mesh, joints = write_box_station(tmp_path)
    rc = run_cli(["plan", str(mesh), str(joints), "--margin", "50", "--quiet",
                  "--tool", "builtin:arc_torch", "-o", str(tmp / "r.csv"),
                  "--tool-csv", str(tmp / "t.csv")])  # fmt: skip
    assert rc in (0, 3)
    tool, _ = load_tool_spec(ToolSpec(builtin="arc_torch"))
    check = _checker(mesh, joints, tool)
    route, _ = csv_poses(tmp / "r.csv")
    path, _ = csv_poses(tmp / "t.csv")
    assert len(route) >= 1 and len(path) > len(route)
    assert set(_route_rows_with_a_pose(tmp / "r.csv")) == {"weld"}  # only verified poses
    assert check.count(route) == [] and check.count(path) == []
    # the check can fail: the first weld's pose moved into the wall (tip at its middle, 30 mm
    # up: the torch leaves through the wall's faces, far from every weld spot)
    bad = route[0].copy()
    bad[:3, 3] = [0.0, 0.0, 30.0]
    assert check.count(bad[None]) == [0]


@pytest.mark.slow
def test_demo_with_the_gun_and_the_robot_writes_no_pose_inside_the_part(tmp_path):
    """The demo station (the shared gun on the KR 150): the route CSV, the tool CSV and every
    sample of the trajectory (FK of its joint rows, the gun on the flange) are outside the part,
    and the trajectory's times strictly increase (a few minutes on 2 cores)."""
    import weldplan
    from weldplan.station.outputs import output_paths, write_plan

    require_shared("robots", "kuka_kr150r3100_2", "kr150r3100_2.urdf")
    require_shared("tools", "spot_welding_gun", "spot_welding_gun.urdf")
    st = weldplan.load_station(ROOT / "examples" / "demo_station.toml")
    out = dataclasses.replace(
        st.outputs, csv=tmp_path / "r.csv", tool_csv=tmp_path / "t.csv",
        trajectory=tmp_path / "q.csv", json=None, post=None,
    )  # fmt: skip
    p = weldplan.plan(dataclasses.replace(st, outputs=out, name="r"), rng=0)
    write_plan(p, output_paths(out, robot=True, tool=True))
    tool, _ = load_tool_spec(st.robots[0].tool)
    check = _checker(st.part.mesh, st.part.welds, tool)
    route, _ = csv_poses(tmp_path / "r.csv")
    path, _ = csv_poses(tmp_path / "t.csv")
    assert len(route) == 15 and set(_route_rows_with_a_pose(tmp_path / "r.csv")) == {"weld"}
    assert check.count(route) == [] and check.count(path) == []
    Q = trajectory_q(tmp_path / "q.csv")
    tcp = p.robot.robot.fk(Q) @ p.robot.robot_route.flange_tcp  # (m, 4, 4) part frame
    assert check.count(tcp) == []
    assert np.all(np.diff(trajectory_t(tmp_path / "q.csv")) > 0)
