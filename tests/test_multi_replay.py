"""The independent replay of a station's timed programs under its interlocks
(weldplan.multi.replay): the mutation test (no interlocks: two robots closer than the clearance;
the zones' interlocks: proven clear under worst-case timing), its own kinematics against the
robot model's, its happens-before on a hand-counted case."""

from __future__ import annotations

import numpy as np
import pytest

from tests import multi_fixtures as mf

CLEARANCE = 5.0


def _zones(robots, timings):
    from weldplan.multi.interference import InterferenceSettings, find_interference
    from weldplan.multi.zones import resolve_zones

    found = find_interference(mf.movers(robots, timings), InterferenceSettings(CLEARANCE))
    return resolve_zones(found)


def test_crossing_robots_meet_without_interlocks_and_are_proven_apart_with_the_zones():
    from weldplan.multi.replay import replay_station

    robots, timings = mf.pair()
    rr = mf.replayed(robots, timings)
    bare = replay_station(rr, (), CLEARANCE)
    # without interlocks every pair of motions (5 x 5) may overlap
    assert not bare.ok and bare.pairs == 25
    assert bare.min_distance < CLEARANCE
    assert "robot1" in bare.failures[0] and "robot2" in bare.failures[0]
    locks = _zones(robots, timings).interlocks
    v = replay_station(rr, locks, CLEARANCE)
    assert v.ok and v.failures == ()
    assert v.min_distance >= CLEARANCE
    assert 0 < v.pairs < bare.pairs  # the interlocks order some pairs: those are not checked
    assert v.closest is not None and "FCL" in v.method


def test_far_robots_are_clear_with_no_fcl_call():
    from weldplan.multi.replay import replay_station

    robots, timings = mf.pair(distance=12000.0)
    v = replay_station(mf.replayed(robots, timings), (), CLEARANCE)
    assert v.ok and v.pairs == 25 and " 0 FCL distances" in v.method
    # a lower bound of the distance there (bounding spheres less the motion bound over a whole
    # motion), far above the clearance
    assert 1000.0 < v.min_distance < 12000.0


def test_the_replay_kinematics_are_its_own_and_agree_with_the_robot_model():
    from weldplan.multi.replay import _fk, _read_chain

    robots, timings = mf.pair()
    rr = mf.replayed(robots, timings)[1]
    chain = _read_chain(rr)
    Q = np.random.default_rng(0).uniform(robots[1].lower, robots[1].upper, (20, 6))
    F = _fk(chain, rr.base, Q)
    np.testing.assert_allclose(F[:, -1], robots[1].fk(Q), atol=1e-6)  # the flange, tool0
    assert [b[0] for b in chain.bodies] == [lk.name for lk in robots[1].links]


def test_the_happens_before_of_one_interlock_counted_by_hand():
    from weldplan.multi.replay import overlapping
    from weldplan.multi.schedule import Interlock

    stops = [np.array([0, 1]), np.array([0, 1])]  # two stops each: rest, move, rest
    # robot 1 at rest at row 1 releases robot 2 waiting at row 0: robot 1's first rest and
    # move end before robot 2's move starts; its last rest lasts to the cycle's end and
    # robot 2's first rest began with the cycle
    got = overlapping(stops, (Interlock("Z1", 0, 1, 1, 0, 1),))
    assert sorted((x, y) for _, x, _, y in got) == [(0, 0), (1, 0), (2, 0), (2, 1), (2, 2)]
    assert len(overlapping(stops, ())) == 9


def test_interlocks_that_wait_in_a_circle_or_name_a_moving_row_are_refused():
    from weldplan.errors import InputError
    from weldplan.multi.replay import overlapping
    from weldplan.multi.schedule import Interlock

    stops = [np.array([0, 2, 3]), np.array([0, 1])]
    circle = (Interlock("Z1", 0, 2, 1, 0, 1), Interlock("Z2", 1, 1, 0, 0, 2))
    with pytest.raises(InputError, match="circle"):
        overlapping(stops, circle)
    with pytest.raises(InputError, match="not a stop"):
        overlapping(stops, (Interlock("Z1", 0, 1, 1, 0, 1),))


def test_the_replay_is_conservative_against_a_fine_brute_force_sampling():
    from tests.test_multi_interference import _brute
    from weldplan.multi.replay import _check_pair, _Found, _run

    robots, timings = mf.pair()
    ra, rb = (_run(r) for r in mf.replayed(robots, timings))
    # robot 1 resting at its start while robot 2 swings into the middle (motions 0 and 1)
    D = _brute(robots, timings, 0, 1)
    assert _check_pair(ra, 0, rb, 1, D + 1.0, _Found()) is not None  # cannot be called clear
    found = _Found()
    assert _check_pair(ra, 0, rb, 1, D - 30.0, found) is None  # proven, its bound is tight
    assert found.low >= D - 30.0  # what it found there is no closer than what it proved
