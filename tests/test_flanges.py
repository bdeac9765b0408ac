"""Flanges from the mesh, against the sheet-metal generator's own ground truth, and per-spot
verdicts for spots that have no stack."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from weldplan.errors import ConfigError, InputError
from weldplan.geometry.flanges import (
    FlangeSettings,
    Sheets,
    find_flanges,
    snap_spots,
)
from weldplan.weld.sheetmetal import SheetFrameSettings, generate_side_frame

pytest.importorskip("open3d")


@pytest.fixture(scope="module")
def station():
    return generate_side_frame(rng=0)


@pytest.fixture(scope="module")
def sheets(station):
    return Sheets(station.sheets)


def _on_flange(point, f) -> bool:
    """Whether ``point`` lies in the overlap of ground-truth flange ``f`` (within 0.5 mm)."""
    e0, e1 = (np.asarray(p) for p in f.edge)
    r0 = np.asarray(f.root[0])
    u = (e1 - e0) / np.linalg.norm(e1 - e0)
    across = (r0 - e0) / np.linalg.norm(r0 - e0)
    d = np.asarray(point) - e0
    along, off = d @ u, d @ across
    plane = abs(d @ np.asarray(f.normal))
    length = np.linalg.norm(e1 - e0)
    return bool(0 <= along <= length and -0.5 <= off <= f.overlap + 0.5 and plane < f.thickness)


@pytest.mark.parametrize("seed", [0, 5])
def test_every_generated_flange_is_found_with_its_gap_and_thickness(seed):
    st = generate_side_frame(rng=seed)
    patches = find_flanges(st.sheets, rng=0)
    assert len(patches) == len(st.flanges)  # and nothing else: a crown is a single skin
    for f in st.flanges:
        mine = [p for p in patches if _on_flange(p.centre, f)]
        assert len(mine) == 1, f.name
        p = mine[0]
        assert p.kind == "lap" and set(p.bodies) == set(f.bodies)
        assert p.gap == pytest.approx(f.gap, abs=0.1)
        assert p.thickness == pytest.approx(f.thickness, abs=0.1)
        assert sorted(p.gauges) == pytest.approx(sorted(f.gauges), abs=0.1)
        assert p.overlap == pytest.approx(f.overlap, abs=0.5)
        assert 0 < p.edge_distance <= f.overlap
        length = np.linalg.norm(np.subtract(*f.edge))
        assert p.length == pytest.approx(length, rel=0.02)


def test_every_spot_snaps_onto_its_own_stack(station, sheets):
    snaps = snap_spots(sheets, station.spots.xyz)
    flanges = {f.name: f for f in station.flanges}
    assert len(snaps) == len(station.spots)
    for k, s in enumerate(snaps):
        f = flanges[station.spot_flange[k]]
        assert s.ok and s.verdict == "stack", s.reason
        assert set(s.stack.joins) == set(f.bodies)
        assert s.distance < 0.01  # the spots are on the faying surfaces already
        assert s.stack.gaps == pytest.approx((f.gap,), abs=0.1)
        assert s.stack.thickness == pytest.approx(f.thickness, abs=0.1)
        assert s.stack.overlap == pytest.approx(f.overlap, abs=0.5)
        # spots sit mid-overlap; the nearest free edge is the flange's (or a member's end)
        assert s.stack.edge_distance <= f.overlap / 2 + 0.5


def test_an_offset_spot_snaps_back_onto_the_faying_surface(station, sheets):
    f = station.flanges[2]
    k = station.spot_flange.index(f.name)
    p = station.spots.xyz[k]
    moved = p + 3.0 * np.asarray(f.normal)  # 3 mm off, out through the hat's flange
    s = snap_spots(sheets, moved[None])[0]
    assert s.ok
    np.testing.assert_allclose(s.position, p, atol=0.01)


def test_spots_without_a_stack_get_a_verdict_and_a_reason(station, sheets):
    sill = station.members[0]
    far = np.array([1000.0, -30.0 - 0.2 - sill.t_inner, 80.0])  # 30 mm from the inner panel
    crown = np.array([1000.0, sill.profile.depth + sill.t_hat, 81.5])  # the hat's crown
    inner = np.array([1000.0, -0.2 - sill.t_inner, 81.5])  # inner panel under the crown
    out = snap_spots(sheets, np.array([far, crown, inner]))
    assert [s.verdict for s in out] == ["no sheet", "single skin", "single skin"]
    assert not any(s.ok for s in out)
    assert "30.0 mm away" in out[0].reason
    assert "sill_hat" in out[1].reason and "sill_inner" in out[2].reason


def test_narrow_overlap_and_no_free_edge_are_named():
    st = generate_side_frame(SheetFrameSettings(overlap=(8.0, 8.0)), rng=0)
    s = snap_spots(st.sheets, st.spots.xyz[:1])[0]
    assert s.verdict == "narrow overlap" and s.stack.overlap == pytest.approx(8.0, abs=0.5)
    # two 600 mm plates lapped all over: a stack, but its edges are 300 mm from the middle
    a = trimesh.creation.box((600, 600, 1.0))
    b = trimesh.creation.box((600, 600, 1.5))
    b.apply_translation((0, 0, 1.25 + 0.3))
    s = snap_spots([a, b], [[0.0, 0.0, 0.65]])[0]
    assert s.verdict == "no free edge" and s.stack.thickness == pytest.approx(2.8, abs=0.01)
    s = snap_spots([a, b], [[0.0, 200.0, 0.65]])[0]  # 100 mm from an edge
    assert s.ok and s.stack.edge_distance == pytest.approx(100.0, abs=1.0)
    assert s.stack.joins == ("body0", "body1") or s.stack.joins == ("body1", "body0")


def test_one_merged_mesh_gives_the_same_stacks_as_named_sheets(station):
    merged = snap_spots(station.combined(), station.spots.xyz[::20])
    named = snap_spots(station.sheets, station.spots.xyz[::20])
    for m, n in zip(merged, named, strict=True):
        assert m.verdict == n.verdict
        assert m.stack.thickness == pytest.approx(n.stack.thickness, abs=1e-6)
        assert m.stack.overlap == n.stack.overlap


def test_a_thin_slab_is_a_wall_only_when_asked():
    slab = trimesh.creation.box((400, 400, 9.0))  # car2's free-standing wall is 8-11 mm
    p = [[0.0, 150.0, 4.5]]
    assert snap_spots(slab, p)[0].verdict == "single skin"
    s = snap_spots(slab, p, FlangeSettings(walls=True))[0]
    assert s.ok and s.verdict == "wall" and s.stack.thickness == pytest.approx(9.0, abs=1e-3)
    assert s.stack.edge_distance == pytest.approx(50.0, abs=1.0)
    np.testing.assert_allclose(s.position, [0.0, 150.0, 0.0], atol=1e-3)  # mid-wall
    thick = trimesh.creation.box((400, 400, 60.0))
    assert snap_spots(thick, [[0, 150, 30.0]], FlangeSettings(walls=True))[0].verdict == "too thick"
    patches = find_flanges(slab, FlangeSettings(walls=True))
    assert len(patches) == 1 and patches[0].kind == "wall"
    assert patches[0].thickness == pytest.approx(9.0, abs=0.1)


def test_bad_input_is_a_one_line_error(station):
    with pytest.raises(InputError, match="finite"):
        snap_spots(station.sheets, [[0.0, np.nan, 0.0]])
    with pytest.raises(ConfigError, match="max_gap"):
        FlangeSettings(max_gap=-1.0)
    with pytest.raises(ConfigError, match="directions"):
        FlangeSettings(directions=5)
    with pytest.raises(InputError, match="no sheet"):
        Sheets([trimesh.Trimesh()])
    assert snap_spots(station.sheets, np.zeros((0, 3))) == ()


def _plate(z: float, size: float = 300.0) -> trimesh.Trimesh:
    """An open square surface (two triangles, no thickness) at height ``z``."""
    h = size / 2
    v = [[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]]
    return trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3]], process=False)


def test_surface_models_stack_by_their_distance_and_a_lone_surface_is_a_single_skin():
    """Mid-surface sheets (no thickness): two surfaces 1.5 mm apart are a stack whose
    thickness is their distance; one surface alone is a single skin, walls or not."""
    s = snap_spots([_plate(0.0), _plate(1.5)], [[0.0, 130.0, 0.7]])[0]
    assert s.ok and s.stack.thickness == pytest.approx(1.5, abs=1e-4)
    assert s.stack.gauges == (0.0, 0.0) and s.stack.edge_distance == pytest.approx(20.0, abs=0.5)
    for walls in (False, True):
        lone = snap_spots([_plate(0.0)], [[0.0, 130.0, 0.5]], FlangeSettings(walls=walls))[0]
        assert lone.verdict == "single skin" and "0.00 mm" in lone.reason
