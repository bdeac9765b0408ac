"""Synthetic weld-joint sets on car2: deterministic, 40-60 mm along their lines, readable."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import require_shared

from weldplan.io.joints import read_joints
from weldplan.weld import synthetic

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def car2():
    path = require_shared("bodies", "car2.obj")
    from weldplan.io.mesh import load_part

    return load_part(path, length=synthetic.CAR2_LENGTH_MM)


@pytest.fixture(scope="module")
def spots(car2):
    return synthetic.generate_spots(car2, rng=0)


@pytest.fixture(scope="module")
def reachable(car2, spots):
    return synthetic.keep_reachable(car2, spots)


def test_deterministic_and_enough(car2, spots):
    again = synthetic.generate_spots(car2, rng=0)
    np.testing.assert_array_equal(spots.xyz, again.xyz)
    assert len(spots) >= max(synthetic.SET_SIZES)
    other = synthetic.generate_spots(car2, rng=1)
    assert len(other) != len(spots) or not np.array_equal(other.xyz, spots.xyz)


def test_spacing_along_lines_and_on_surface(car2, spots):
    lo, hi = synthetic.SPACING_MM
    gaps = []
    for li in np.unique(spots.line):
        p = spots.xyz[spots.line == li]
        gaps.append(np.linalg.norm(np.diff(p, axis=0), axis=1))
    gaps = np.concatenate(gaps)
    # chords along a polyline are at most the arc gap (most lines are straight); a spot dropped
    # for crowding another line leaves a wider gap
    inside = (gaps >= lo - 5.0) & (gaps <= hi + 1e-6)
    assert inside.mean() > 0.8, inside.mean()
    assert lo <= np.median(gaps) <= hi
    d = np.abs(car2.nearest.signed_distance(spots.xyz[:200]))
    assert d.max() < 1e-3
    np.testing.assert_allclose(np.linalg.norm(spots.directions, axis=1), 1.0)


@pytest.mark.slow
def test_unreachable_spots_are_dropped(spots, reachable):
    # car2 closes a few volumes: spots facing into one have no route to the rest (3 at seed 0)
    assert 0 < len(spots) - len(reachable) <= 10
    kept = set(map(tuple, reachable.xyz))
    assert kept <= set(map(tuple, spots.xyz))
    assert len(reachable) >= max(synthetic.SET_SIZES)


@pytest.mark.slow
def test_sets_are_nested_compact_and_match_assets(reachable):
    spots = reachable
    j50, st50 = synthetic.select_set(spots, 50)
    j200, _ = synthetic.select_set(spots, 200)
    assert set(map(tuple, j50.xyz)) <= set(map(tuple, j200.xyz))
    assert len(set(st50)) == 1  # one station
    for n in synthetic.SET_SIZES:
        path = ROOT / "assets" / "car2" / f"car2_synthetic_{n}.csv"
        assert "SYNTHETIC" in path.read_text().splitlines()[0]
        got = read_joints(path)
        want, _ = synthetic.select_set(spots, n)
        assert got.ids == want.ids
        np.testing.assert_allclose(got.xyz, want.xyz, atol=1e-3)
        np.testing.assert_allclose(got.directions, want.directions, atol=1e-5)


@pytest.fixture(scope="module")
def whole_body(car2):
    return synthetic.generate_spots(car2, rng=0, **synthetic.PROFILES["whole-body"])


def _stations_of(mesh, xyz):
    """Station labels recomputed from the positions (module docstring, step 4)."""
    bmin, bmax = mesh.bounds
    zone = np.clip(((xyz[:, 0] - bmin[0]) / (bmax[0] - bmin[0]) * 4).astype(int), 0, 3)
    lr = np.where(xyz[:, 1] < 0.5 * (bmin[1] + bmax[1]), "R", "L")
    return np.array([f"Z{z + 1}{s}" for z, s in zip(zone, lr, strict=True)])


def test_whole_body_profile_gives_distinct_labelled_spots_on_both_flanges(car2, whole_body):
    from scipy.spatial import cKDTree

    from weldplan.geometry.collision import CollisionModel

    spots = whole_body
    assert len(spots) >= synthetic.WHOLE_BODY_SIZE  # a whole body's count (4,524 at seed 0)
    # distinct: no two spots nearer than the profile's gap, whichever lines they are on
    d, _ = cKDTree(spots.xyz).query(spots.xyz, 2)
    assert d[:, 1].min() >= synthetic.PROFILES["whole-body"]["min_gap"] - 1e-9
    # both flanges of the edge lines carry spots, and the lines of the two are numbered apart
    assert set(np.unique(spots.flange)) == {0, 1}
    assert not set(spots.line[spots.flange == 0]) & set(spots.line[spots.flange == 1])
    # labels are the regions of the positions; every label is a station name
    np.testing.assert_array_equal(spots.stations, _stations_of(car2, spots.xyz))
    # on the surface, unit approach directions, and the approach cone is open
    pick = np.random.default_rng(0).choice(len(spots), 300, replace=False)
    assert np.abs(car2.nearest.signed_distance(spots.xyz[pick])).max() < 1e-3
    np.testing.assert_allclose(np.linalg.norm(spots.directions, axis=1), 1.0)
    probe = np.asarray(synthetic.APPROACH_PROBE_MM)
    q = spots.xyz[pick, None, :] + spots.directions[pick, None, :] * probe[None, :, None]
    clear = CollisionModel(car2).clearance(q.reshape(-1, 3)).reshape(len(pick), len(probe))
    assert np.all(clear >= synthetic.APPROACH_OPEN * probe - 1e-6)
    # denser than the station rule: the median pitch along a line within 20-30 mm
    gaps = np.concatenate(
        [
            np.linalg.norm(np.diff(spots.xyz[spots.line == li], axis=0), axis=1)
            for li in np.unique(spots.line)
        ]
    )
    assert 20.0 <= np.median(gaps) <= 30.0


def test_whole_body_profile_keeps_the_station_rule_apart(car2, spots, whole_body):
    # the station profile is the generator's default, so the 50/200/1000 sets stay as they were
    again = synthetic.generate_spots(car2, rng=0, **synthetic.PROFILES["station"])
    np.testing.assert_array_equal(again.xyz, spots.xyz)
    assert set(np.unique(spots.flange)) == {0}
    assert len(whole_body) > 3 * len(spots)
    with pytest.raises(ValueError, match="profile"):
        synthetic.car2_joints(10, profile="bogus", mesh=car2)
    with pytest.raises(ValueError, match="flanges"):
        synthetic.generate_spots(car2, flanges=(0, 2))


def test_whole_body_asset_is_the_generator_output(car2, whole_body):
    """assets/car2/car2_synthetic_4000.csv: 4000 distinct spots of the whole-body profile,
    labelled synthetic, each with its station label (keep_reachable, which builds the whole
    body's grid, is the only step not repeated here: it dropped 12 of the 4,524)."""
    from scipy.spatial import cKDTree

    path = ROOT / "assets" / "car2" / f"car2_synthetic_{synthetic.WHOLE_BODY_SIZE}.csv"
    text = path.read_text().splitlines()
    assert "SYNTHETIC" in text[0] and "whole-body" in text[0]
    got = read_joints(path)
    assert len(got.ids) == len(set(got.ids)) == synthetic.WHOLE_BODY_SIZE
    d, k = cKDTree(whole_body.xyz).query(got.xyz)
    assert d.max() < 1e-3  # every joint is a generated spot (written to 1e-3 mm)
    np.testing.assert_allclose(got.directions, whole_body.directions[k], atol=1e-5)
    stations = np.array([row.split(",")[-1] for row in text[2:]])
    np.testing.assert_array_equal(stations, whole_body.stations[k])
    assert all(i.startswith(s + "-") for i, s in zip(got.ids, stations, strict=True))
    assert len(np.unique(stations)) >= 6  # the whole body, not one station
