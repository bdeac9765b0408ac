"""The B-pillar station (weldplan.weld.pillar_spots): only the pillar's flanges carry spots, each
between the two sheets of its flange; the committed files are what the generator writes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from weldplan.io.joints import read_joints
from weldplan.weld import pillar_spots as ps
from weldplan.weld.sheetmetal import generate_side_frame, read_sheets

ROOT = Path(__file__).resolve().parents[1]
ASSETS = ROOT / "assets" / "frame_pillar"


@pytest.fixture(scope="module")
def station():
    return ps.pillar_station(rng=0)


def test_the_spots_are_the_full_frames_pillar_spots_in_their_order(station):
    full = generate_side_frame(rng=0)
    mine = [k for k, f in enumerate(full.spot_flange) if f.startswith("bpillar_")]
    assert station.spots.ids == tuple(full.spots.ids[k] for k in mine)
    np.testing.assert_array_equal(station.spots.xyz, full.spots.xyz[mine])
    assert set(station.spot_flange) == {"bpillar_a", "bpillar_b"}
    assert station.sheets.keys() == full.sheets.keys()  # the sill and rail stay as obstacles


def test_each_spot_lies_between_the_two_sheets_of_its_flange(station):
    """A ray along the approach from each spot leaves through the sheet on the torch's side
    first; the opposite ray meets the other sheet of the flange (trimesh's ray casts)."""
    truth = {f.name: f for f in station.flanges}
    d = station.spots.directions
    for k, P in enumerate(station.spots.xyz):
        f = truth[station.spot_flange[k]]
        near, far = [], []
        for name, m in station.sheets.items():
            for sign, got in ((1.0, near), (-1.0, far)):
                loc, _, _ = m.ray.intersects_location([P], [sign * d[k]])
                if len(loc):
                    got.append((float(np.linalg.norm(loc - P, axis=1).min()), name))
        assert min(near)[1] in f.bodies and min(far)[1] in f.bodies
        assert min(near)[1] != min(far)[1]
        assert min(near)[0] + min(far)[0] == pytest.approx(f.gap, abs=1e-5)


def test_another_seed_gives_other_spots_and_a_bad_member_is_an_error(station):
    assert not np.array_equal(ps.pillar_station(rng=1).spots.xyz[:5], station.spots.xyz[:5])
    with pytest.raises(ValueError, match="no spot on a member named 'door'"):
        ps.pillar_station(rng=0, member="door")


def test_the_committed_station_is_what_the_generator_writes(tmp_path):
    assert ps.main([str(tmp_path / "out"), "--seed", "0"]) == 0
    for name in ("body.obj", "spots.csv", "truth.json"):
        assert (tmp_path / "out" / name).read_bytes() == (ASSETS / name).read_bytes(), name
    spots = read_joints(ASSETS / "spots.csv")
    assert len(spots) == 46 and all(i.startswith("bpillar_") for i in spots.ids)
    assert (ASSETS / "spots.csv").read_text().startswith("# SYNTHETIC weld spots (46)")
    sheets = read_sheets(ASSETS / "body.obj")
    assert all(isinstance(m, trimesh.Trimesh) and m.is_watertight for m in sheets.values())
