"""Routes record what they were planned against, and verify refuses another mesh, scale or
clearance (issue 14, 2.3), and a NaN, zero or negative clearance (2.4)."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from tests.route_fixtures import CLEARANCE, box_part, box_route
from weldplan.cli import main
from weldplan.errors import InputError
from weldplan.io.mesh import file_sha256, geometry_hash, load_part
from weldplan.weld.route import Route
from weldplan.weld.verify import verify_route

JOINTS_CSV = "id,x,y,z\nA,-40,0,0\nB,40,0,0\nC,-40,60,0\n"


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """The box scene planned from files; its route saved as JSON."""
    pytest.importorskip("weldplan.weld.local")
    from weldplan.weld.cell import load_cell
    from weldplan.weld.pipeline import PlanConfig, plan_route

    tmp = tmp_path_factory.mktemp("prov")
    mesh = tmp / "box.stl"
    box_part().export(mesh)
    joints = tmp / "joints.csv"
    joints.write_text(JOINTS_CSV)
    cell = load_cell(mesh, joints)
    route = plan_route(cell, config=PlanConfig(planner="exact"), rng=0)
    path = tmp / "route.json"
    path.write_text(route.to_json())
    return tmp, mesh, joints, cell, route, path


def test_route_json_records_the_mesh_units_scale_and_clearance(planned):
    _, mesh, joints, cell, route, path = planned
    prov = json.loads(path.read_text())["provenance"]
    assert prov["mesh"]["geometry_sha256"] == geometry_hash(cell.part)
    assert prov["mesh"]["file_sha256"] == file_sha256(mesh)
    assert prov["mesh"]["file"] == str(mesh)
    assert (prov["mesh"]["units"], prov["mesh"]["scale"]) == ("mm", 1.0)
    assert prov["mesh"]["repairs"] == {"degenerate_faces": 0, "duplicate_faces": 0}
    assert prov["clearance"] == 5.0
    assert Route.from_json(path.read_text()).provenance == route.provenance


def test_verify_accepts_the_same_mesh_loaded_again(planned):
    _, mesh, _, _, route, _ = planned
    assert verify_route(route, load_part(mesh)).ok


def test_verify_refuses_the_same_file_at_another_scale_or_units(planned):
    _, mesh, _, _, route, _ = planned
    with pytest.raises(InputError, match=r"this mesh file at units 'mm', scale 1\.0.*scale 2\.0"):
        verify_route(route, load_part(mesh, scale=2.0))
    with pytest.raises(InputError, match="units 'm'"):
        verify_route(route, load_part(mesh, units="m"))


def test_verify_refuses_another_mesh(planned, tmp_path):
    _, _, _, _, route, _ = planned
    other = box_part()
    other.apply_translation([0.0, 0.0, 0.5])
    with pytest.raises(InputError, match="planned for another mesh"):
        verify_route(route, other)


def test_verify_refuses_another_clearance_but_takes_its_own(planned):
    _, mesh, _, _, route, _ = planned
    part = load_part(mesh)
    with pytest.raises(InputError, match="planned at clearance 5 mm, not 3 mm"):
        verify_route(route, part, clearance=3.0)
    assert verify_route(route, part, clearance=5.0).ok


def test_a_route_without_provenance_is_verified_with_a_warning(planned, caplog):
    _, mesh, _, _, route, _ = planned
    old = dataclasses.replace(route, provenance={})
    with caplog.at_level("WARNING", logger="weldplan.weld.verify"):
        assert verify_route(old, load_part(mesh)).ok
    assert "no provenance" in caplog.text
    d = json.loads(route.to_json())
    del d["provenance"]  # a JSON written before provenance existed
    assert Route.from_dict(d).provenance == {}


@pytest.mark.parametrize("bad", [math.nan, 0.0, -1.0, math.inf, "five"])
def test_verify_route_rejects_a_bad_clearance(bad):
    with pytest.raises(InputError, match="clearance must be a positive number of mm"):
        verify_route(box_route(), box_part(), clearance=bad)
    assert verify_route(box_route(), box_part(), clearance=CLEARANCE).ok


def test_cli_verify_refuses_a_bad_clearance_and_another_scale(planned, capsys):
    _, mesh, _, _, _, path = planned
    for bad in ("nan", "0", "-1"):
        with pytest.raises(SystemExit) as e:
            main(["verify", str(path), str(mesh), "--clearance", bad])
        assert e.value.code == 2
        err = capsys.readouterr().err
        assert "--clearance" in err and "Traceback" not in err
    assert main(["verify", str(path), str(mesh), "--scale", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--units/--scale/--length" in err
    assert main(["verify", str(path), str(mesh)]) == 0
    assert "route ok" in capsys.readouterr().out
