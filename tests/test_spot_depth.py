"""Spots on the faying surface of a sheet stack: the approach cone starts ``spot_depth`` mm out.

A lap joint's spot lies between two sheets, so the first millimetres of any approach run through
the near sheet; with ``spot_depth`` at least that deep the route is planned and verified, below
it the independent check refuses it, and a route that drops its recorded depth is refused too.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh

from weldplan.errors import InputError
from weldplan.io.joints import Joints
from weldplan.weld.cell import build_cell
from weldplan.weld.pipeline import plan_route
from weldplan.weld.verify import APPROACH_EXEMPT_MM, approach_pieces, verify_route

GAUGE, GAP = 1.5, 0.2


def _stack() -> trimesh.Trimesh:
    """Two 1.5 mm sheets 0.2 mm apart, faying surfaces at z = 0 and z = 0.2."""
    lower = trimesh.creation.box(extents=[200.0, 120.0, GAUGE])
    lower.apply_translation([0.0, 0.0, -GAUGE / 2])
    upper = trimesh.creation.box(extents=[200.0, 120.0, GAUGE])
    upper.apply_translation([0.0, 0.0, GAP + GAUGE / 2])
    return trimesh.util.concatenate([lower, upper])


def _spots() -> Joints:
    """Three spots in the gap, mid-way between the sheets, welded from above (+z)."""
    xyz = np.array([[-50.0, 0.0, GAP / 2], [0.0, 10.0, GAP / 2], [50.0, 0.0, GAP / 2]])
    return Joints(ids=("a", "b", "c"), xyz=xyz, directions=np.tile([0.0, 0.0, 1.0], (3, 1)))


def test_approach_pieces_start_at_the_depth_and_lie_in_the_moved_cone():
    spot, virt = np.zeros(3), np.array([0.0, 0.0, 20.0])
    A0, B0, r0 = approach_pieces(spot, virt, 5.0, pieces=4)
    A, B, r = approach_pieces(spot, virt, 5.0, pieces=4, depth=0.0)
    np.testing.assert_array_equal(A0, A)  # depth 0 is the spot on the surface, unchanged
    np.testing.assert_array_equal(r0, r)
    A, B, r = approach_pieces(spot, virt, 5.0, pieces=4, depth=3.0)
    assert A[0][2] == pytest.approx(3.0 + APPROACH_EXEMPT_MM)
    np.testing.assert_allclose(B[-1], virt)
    np.testing.assert_array_less(r, 5.0 * (A[:, 2] - 3.0) / (20.0 - 3.0) + 1e-12)
    assert len(approach_pieces(spot, virt, 5.0, depth=19.8)[0]) == 0  # nothing left to check


def test_a_spot_between_sheets_is_planned_and_verified_with_its_depth():
    part = _stack()
    depth = GAUGE + GAP / 2  # the near sheet and half the gap
    cell = build_cell(part, _spots(), pitch=2.0, clearance=3.0, margin=30.0, spot_depth=depth)
    route = plan_route(cell, rng=0)
    assert route.settings["spot_depth"] == pytest.approx(depth)
    rep = verify_route(route, part)
    assert rep.ok, rep.describe()
    # the route without its depth: the approaches run through the near sheet
    bare = dataclasses.replace(
        route, settings={k: v for k, v in route.settings.items() if k != "spot_depth"}
    )
    rep = verify_route(bare, part)
    assert not rep.ok and "cone" in rep.describe()
    # too shallow a depth: the cone still meets the sheet the gun presses
    shallow = dataclasses.replace(route, settings={**route.settings, "spot_depth": GAUGE / 2})
    assert not verify_route(shallow, part).ok


def test_spots_on_the_surface_record_no_depth():
    part = _stack()
    top = Joints(
        ids=("a", "b"),
        xyz=np.array([[-50.0, 0.0, GAP + GAUGE], [50.0, 0.0, GAP + GAUGE]]),
        directions=np.tile([0.0, 0.0, 1.0], (2, 1)),
    )
    route = plan_route(build_cell(part, top, pitch=2.0, clearance=3.0, margin=30.0), rng=0)
    assert "spot_depth" not in route.settings
    assert verify_route(route, part).ok


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf")])
def test_a_bad_depth_is_refused(bad):
    with pytest.raises(InputError, match="spot_depth"):
        build_cell(_stack(), _spots(), pitch=2.0, clearance=3.0, margin=30.0, spot_depth=bad)


def test_a_route_with_a_bad_recorded_depth_is_refused():
    part = _stack()
    cell = build_cell(part, _spots(), pitch=2.0, clearance=3.0, margin=30.0, spot_depth=1.6)
    route = plan_route(cell, rng=0)
    bad = dataclasses.replace(route, settings={**route.settings, "spot_depth": "deep"})
    with pytest.raises(InputError, match="spot_depth"):
        verify_route(bad, part)


def _files(tmp_path):
    mesh = tmp_path / "stack.stl"
    _stack().export(mesh)
    csv = tmp_path / "spots.csv"
    rows = ["id,x,y,z,nx,ny,nz"] + [
        f"{i},{x},{y},{z},0,0,1" for i, (x, y, z) in zip("abc", _spots().xyz, strict=True)
    ]
    csv.write_text("\n".join(rows) + "\n")
    return mesh, csv


def test_the_cli_and_the_station_file_take_the_depth(tmp_path, capsys):
    from weldplan.cli import main
    from weldplan.io.export import read_route

    mesh, csv = _files(tmp_path)
    common = ["--pitch", "2", "--clearance", "3", "--margin", "30", "--quiet"]
    out = tmp_path / "r.csv"
    assert main(["plan", str(mesh), str(csv), "-o", str(out), "--json", str(tmp_path / "r.json"),
                 "--spot-depth", "1.6", *common]) == 0  # fmt: skip
    assert read_route(tmp_path / "r.json").settings["spot_depth"] == pytest.approx(1.6)
    assert main(["verify", str(tmp_path / "r.json"), str(mesh)]) == 0
    toml = tmp_path / "st.toml"
    toml.write_text(
        f'clearance = 3.0\n[part]\nmesh = "{mesh.name}"\nwelds = "{csv.name}"\n'
        "[cell]\npitch = 2.0\nmargin = 30.0\nspot_depth = 1.6\n"
        f'[output]\ncsv = "{tmp_path / "s.csv"}"\n'
    )
    assert main(["plan", str(toml), "--quiet"]) == 0
    def rows(f):  # the header names each station; the route is the same
        return [r for r in f.read_text().splitlines() if not r.startswith("#")]

    assert rows(tmp_path / "s.csv") == rows(out)
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:  # argparse's usage error, one line, exit 2
        main(["plan", str(mesh), str(csv), "-o", str(out), "--spot-depth", "-1"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "spot_depth" in err and "Traceback" not in err
