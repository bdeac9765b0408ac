"""The interference check's sphere shortcuts (weldplan.multi.sweep): the bounds they rest on
against FCL, and the check with them against the check without them (the same conflicts, the
same distances, every FCL query either asked or answered by the spheres)."""

from __future__ import annotations

import numpy as np
import pytest

from tests import multi_fixtures as mf

CLEARANCE = 5.0


def _gun_pair(tmp_path, distance=4000.0):
    """Two KR 150 ``distance`` mm apart crossing in the middle (tests/multi_fixtures.py), each
    with the station's spot gun (tests/test_multi_cli.py's crossing pair)."""
    from tests.test_multi_cli import _station_toml
    from weldplan import load_station
    from weldplan.multi.interference import MovingRobot
    from weldplan.station.mount import mount_tool

    robots, timings = mf.pair(distance=distance)
    bases = ((-distance / 2, 0.0, 0.0, 0.0), (distance / 2, 0.0, 0.0, 180.0))
    station = load_station(_station_toml(tmp_path, ["1", "9"], bases=bases))
    movers = []
    for k, (r, t, spec) in enumerate(zip(robots, timings, station.robots, strict=True)):
        m = mount_tool(spec.tool, r)
        movers.append(MovingRobot(f"robot{k + 1}", r, t, m.tool, m.flange_tcp))
    return movers


def _both(movers, clearance=CLEARANCE):
    from weldplan.multi.interference import InterferenceSettings, find_interference

    full = find_interference(movers, InterferenceSettings(clearance, prune=False))
    pruned = find_interference(movers, InterferenceSettings(clearance, prune=True))
    return full, pruned


def _same(full, pruned):
    assert pruned.conflicts == full.conflicts  # motions, bodies, distances, proven: all equal
    assert pruned.min_distance == full.min_distance
    assert (pruned.robot_pairs, pruned.pairs_checked) == (full.robot_pairs, full.pairs_checked)
    # the same search: every query of the full check is asked or answered by the spheres
    assert full.fcl_skipped == 0
    assert pruned.fcl_calls + pruned.fcl_skipped == full.fcl_calls


def test_the_sphere_bounds_hold_against_fcl_on_random_poses():
    from weldplan.multi.interference import pair_distance
    from weldplan.multi.sweep import sphere_bounds

    bodies, other, covers = _two_sets()
    rng = np.random.default_rng(0)
    seen_close = 0
    small = [k for k, b in enumerate(bodies) if b.name in ("link_4", "link_5", "link_6")]
    for _ in range(20):
        p, q = rng.choice(small, size=2)
        Ta, Tb = np.eye(4), _random_pose(rng)
        lb, ub = sphere_bounds(covers[p], Ta, covers[q], Tb)
        d = pair_distance(bodies[p].obj, Ta, other[q].obj, Tb)
        assert lb <= d + 1e-9 and d <= ub + 1e-9
        seen_close += d < 200.0
    assert seen_close >= 3  # poses close enough for the bounds to matter


def _two_sets():
    """The bodies of a KR 150 twice (each its own FCL objects) and their covers (made when
    first asked)."""
    from weldplan.multi.interference import robot_bodies
    from weldplan.multi.sweep import body_cover

    robots, timings = mf.pair()
    ms = mf.movers(robots, timings)
    bodies, other = robot_bodies(ms[0]), robot_bodies(ms[1])

    class Covers(dict):
        def __missing__(self, k):
            self[k] = body_cover(bodies[k])
            return self[k]

    return bodies, other, Covers()


def _random_pose(rng):
    from scipy.spatial.transform import Rotation

    T = np.eye(4)
    T[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    T[:3, 3] = rng.normal(0.0, 400.0, 3)
    return T


def test_a_node_is_settled_only_as_its_fcl_distance_would_settle_it():
    from weldplan.multi.interference import pair_distance
    from weldplan.multi.sweep import CLEAR, HALVE, settled

    bodies, other, covers = _two_sets()
    rng = np.random.default_rng(1)
    said = {CLEAR: 0, HALVE: 0}
    for _ in range(80):
        p, q = rng.integers(len(bodies), size=2)
        Tb, reach = _random_pose(rng), float(rng.uniform(0.0, 300.0))
        leaf = bool(rng.integers(2))
        known = settled(covers[p], np.eye(4), covers[q], Tb, reach, CLEARANCE, leaf)
        d = pair_distance(bodies[p].obj, np.eye(4), other[q].obj, Tb)
        if known == CLEAR:
            assert d - reach >= CLEARANCE
        elif known == HALVE:
            assert not leaf and d >= CLEARANCE and d - reach < CLEARANCE
        said[known] = said.get(known, 0) + 1
    assert said[CLEAR] > 0 and said[HALVE] > 0


@pytest.mark.parametrize("clearance", [5.0, pytest.param(150.0, marks=pytest.mark.slow)])
def test_the_pruned_check_finds_what_the_full_check_finds_on_bare_arms(clearance, monkeypatch):
    from weldplan.multi import sweep

    # the links alone are below the size the spheres are asked for: ask them for every pair
    monkeypatch.setattr(sweep, "MIN_TRIANGLES", 0)
    robots, timings = mf.pair()
    full, pruned = _both(mf.movers(robots, timings), clearance)
    assert full.conflicts  # the arms cross: something to find
    _same(full, pruned)
    assert pruned.fcl_calls < full.fcl_calls


def test_the_pruned_check_finds_what_the_full_check_finds_with_the_spot_guns(tmp_path):
    movers = _gun_pair(tmp_path)
    full, pruned = _both(movers)
    assert any(c.proven for c in full.conflicts) and len(full.conflicts) < full.pairs_checked
    _same(full, pruned)
    assert pruned.fcl_calls <= full.fcl_calls / 4
