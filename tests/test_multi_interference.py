"""Robot-robot interference (weldplan.multi.interference) and the interlocked zones that order
it (weldplan.multi.zones), on two shared KR 150 with synthetic timed routes
(tests/multi_fixtures.py)."""

from __future__ import annotations

import numpy as np
import pytest

from tests import multi_fixtures as mf

CLEARANCE = 5.0


def _find(robots, timings, clearance=CLEARANCE):
    from weldplan.multi.interference import InterferenceSettings, find_interference

    return find_interference(mf.movers(robots, timings), InterferenceSettings(clearance))


def test_the_motions_cut_a_timed_route_at_its_stops():
    from weldplan.multi.interference import robot_motions

    robots, (ta, _) = mf.pair()
    motions, spans = robot_motions(ta)
    assert [m.kind for m in motions] == ["rest", "move", "rest", "move", "rest"]
    assert [(m.start_row, m.end_row) for m in motions] == [(0, 0), (0, 1), (1, 1), (1, 2), (2, 2)]
    # the weld at row 1 is the rest there; the moves are the timing's own segments
    assert motions[2].end - motions[2].start == pytest.approx(mf.WELD_S)
    assert motions[1].end - motions[1].start == pytest.approx(ta.segments[0].duration)
    assert motions[-1].end == pytest.approx(ta.total)
    # a move's samples run from the arrival at its first stop (the dwell there: the same
    # configuration) to the arrival at its last
    for m, (i0, i1) in zip(motions, spans, strict=True):
        assert ta.t[i0] == ta.row_times[m.start_row] and ta.t[i1] == ta.row_times[m.end_row]


def test_facing_robots_conflict_where_their_arms_cross_and_the_zones_order_every_conflict():
    from weldplan.multi.schedule import station_schedule
    from weldplan.multi.zones import happens_before, ordered, resolve_zones

    robots, timings = mf.pair()
    found = _find(robots, timings)
    cells = {(c.x, c.y) for c in found.conflicts}
    # both arms stretched to A1 = 0 overlap (the bases 3 m apart, 1.965 m of arm each): the
    # moves into the middle and the welds there conflict, witnessed by FCL
    assert {(1, 1), (2, 2), (3, 3)} <= cells
    assert all(c.proven and c.distance < CLEARANCE for c in found.conflicts if (c.x, c.y) == (2, 2))
    # the rests at the ends (arms swung apart) do not
    assert not any(0 in cell or 4 in cell for cell in cells)
    zones = resolve_zones(found)
    assert len(zones.interlocks) == 1 and len(zones.zones) == 1  # one zone: one interlock
    lock = zones.interlocks[0]
    assert (lock.zone, lock.signal) == ("Z1", 1)
    sizes = [len(m) + 1 for m in found.motions]
    vc = happens_before(sizes, [(lock.first, 2 * lock.release_row, lock.second,
                                 2 * lock.wait_row + 1)])  # fmt: skip
    assert all(ordered(vc, c.a, c.x, c.b, c.y) for c in found.conflicts)
    # the station's cycle grows by exactly the waits: each robot ends at its own time plus its
    # waits, and the waiting robot waits until the other is out of the zone
    s = station_schedule(["r1", "r2"], timings, zones.interlocks)
    for r, t in enumerate(timings):
        assert s.cycle_times[r] == pytest.approx(t.total + s.waiting[r], abs=1e-9)
    w = lock.second
    assert s.waiting[1 - w] == 0.0
    release = timings[lock.first].row_times[lock.release_row] + (
        mf.WELD_S if lock.release_row in timings[lock.first].weld_rows else 0.0)  # fmt: skip
    assert s.waiting[w] == pytest.approx(release - timings[w].row_times[lock.wait_row], abs=1e-9)
    assert s.cycle_time > max(t.total for t in timings)


def test_far_apart_robots_have_no_conflict_and_cost_nothing():
    from weldplan.multi.schedule import station_schedule
    from weldplan.multi.zones import resolve_zones

    robots, timings = mf.pair(distance=12000.0)
    found = _find(robots, timings)
    assert found.conflicts == () and found.fcl_calls == 0
    zones = resolve_zones(found)
    assert zones.interlocks == () and zones.zones == ()
    s = station_schedule(["r1", "r2"], timings, zones.interlocks)
    assert s.waiting == (0.0, 0.0)
    assert s.cycle_time == pytest.approx(max(t.total for t in timings), abs=1e-12)


def _brute(robots, timings, x, y, refine=4):
    """mm: the smallest FCL distance between robot 1 over motion ``x`` and robot 2 over motion
    ``y``, every pair of configurations of their samples refined ``refine`` times (linear in
    joint space), every pair of bodies: a body pair is skipped only when the distance of the
    two bounding balls of their vertices is already above the best (exact)."""
    from weldplan.multi.interference import pair_distance, robot_bodies, robot_motions

    ms = mf.movers(robots, timings)
    Qs = []
    for k, m in ((0, x), (1, y)):
        i0, i1 = robot_motions(timings[k])[1][m]
        Q = timings[k].q[i0 : i1 + 1]
        s = np.linspace(0, 1, refine + 1)[1:, None]
        Qs.append(
            np.vstack([Q[:1]] + [a + s * (b - a) for a, b in zip(Q[:-1], Q[1:], strict=True)])
        )
    Fa, Fb = robots[0].link_frames(Qs[0]), robots[1].link_frames(Qs[1])
    ba, bb = robot_bodies(ms[0]), robot_bodies(ms[1])

    def balls(bodies, F):  # (n, b, 3) centres of each body's bounding ball, (b,) radii
        c = np.stack([F[:, x.frame, :3, :3] @ x.centre + F[:, x.frame, :3, 3] for x in bodies], 1)
        return c, np.array([x.radius for x in bodies])

    (ca, ra), (cb, rb) = balls(ba, Fa), balls(bb, Fb)
    gap = np.linalg.norm(ca[:, None, :, None] - cb[None, :, None], axis=-1)
    gap -= ra[:, None] + rb[None]
    best = np.inf
    for i, j, p, q in sorted(np.ndindex(gap.shape), key=lambda k: gap[k]):
        if gap[i, j, p, q] >= best:
            break  # every pair left is farther apart than the best
        x, y = ba[p], bb[q]
        best = min(best, pair_distance(x.obj, Fa[i, x.frame], y.obj, Fb[j, y.frame]))
    return best


def test_the_check_is_conservative_against_a_fine_brute_force_sampling():
    robots, timings = mf.pair()
    # robot 1 resting at its start (A1 = 1 rad) while robot 2 swings into the middle
    D = _brute(robots, timings, 0, 1)
    assert 100.0 < D < 1000.0
    # a clearance above the true distance: the check cannot call the pair clear
    cells = {(c.x, c.y) for c in _find(robots, timings, D + 1.0).conflicts}
    assert (0, 1) in cells
    # well under it (by more than the motion between two samples): proven clear
    cells = {(c.x, c.y) for c in _find(robots, timings, D - 60.0).conflicts}
    assert (0, 1) not in cells


def _synthetic(conflicts, weld=10.0):
    """An Interference of two robots of four stops each (robot 1 welds ``weld`` s at its first
    stop, so robot 2 gets everywhere first) and the given conflict cells."""
    from weldplan.multi.interference import Conflict, Interference, robot_motions

    robots, _ = mf.pair(distance=12000.0)
    ta = mf.sweep(robots[0], (1.0, 0.5, 0.0, -0.5), weld_rows=(0,), weld_time=weld)
    tb = mf.sweep(robots[1], (1.0, 0.5, 0.0, -0.5), weld_rows=(), weld_time=0.0)
    motions = (robot_motions(ta)[0], robot_motions(tb)[0])
    cs = tuple(Conflict(0, x, 1, y, 0.0, True) for x, y in conflicts)
    return Interference(("r1", "r2"), CLEARANCE, motions, cs, ((0, 1),), 49, 0, 0.0), (ta, tb)


def test_a_deadlock_prone_order_is_resolved_the_other_way():
    from weldplan.errors import PlanningError
    from weldplan.multi.schedule import Interlock, station_schedule
    from weldplan.multi.zones import resolve_zones

    # robot 1's first rest conflicts with robot 2's move 3 (forced: robot 1 leaves first, so
    # its move 1 ends before robot 2's move 3 starts); robot 1's rest 2 conflicts with robot
    # 2's move 5, which the schedule without interlocks reaches first (robot 1 welds 10 s at the
    # start): taking that order (robot 2 first) deadlocks with the first
    found, timings = _synthetic([(0, 3), (2, 5)])
    naive = (Interlock("Z1", 0, 1, 1, 1, 1), Interlock("Z2", 1, 3, 0, 0, 2))
    with pytest.raises(PlanningError, match="deadlock"):
        station_schedule(["r1", "r2"], timings, naive)
    # the zones take the second order from the schedule with the first interlock's wait in it,
    # where robot 1 is there first: no circle
    zones = resolve_zones(found)
    assert len(zones.zones) == 2 and not any(z.reversed for z in zones.zones)
    assert [(lk.first, lk.second) for lk in zones.interlocks] == [(0, 1), (0, 1)]
    s = station_schedule(["r1", "r2"], timings, zones.interlocks)  # no deadlock
    assert s.cycle_times[1] == pytest.approx(timings[1].total + s.waiting[1], abs=1e-9)


def test_an_implied_interlock_is_dropped_and_an_unorderable_pair_is_an_error():
    from weldplan.errors import PlanningError
    from weldplan.multi.zones import resolve_zones

    # (1, 5) is ordered by the interlock of (3, 3): robot 1 ends its move 3 before robot 2
    # starts its move 3, so before its move 5
    zones = resolve_zones(_synthetic([(3, 3), (1, 5)])[0])
    assert len(zones.interlocks) == 1
    # robot 1 leaves its first stop at once, as robot 2 rests at its own: robot 1 first would
    # need robot 2 to leave its start after robot 1's move, which no program can: robot 2
    # goes first, against the nominal tie
    zones = resolve_zones(_synthetic([(1, 0)], weld=0.0)[0])
    assert [z.reversed for z in zones.zones] == [True]
    lock = zones.interlocks[0]
    assert (lock.first, lock.release_row, lock.second, lock.wait_row) == (1, 1, 0, 0)
    # both robots' first rests: at the cycle's start together, no interlock can part them
    with pytest.raises(
        PlanningError, match="robot 1 at rest at row 0 and robot 2 at rest at row 0"
    ):
        resolve_zones(_synthetic([(0, 0)])[0])
    # not strict: that pair is listed, the others ordered
    zones = resolve_zones(_synthetic([(0, 0), (3, 3)])[0], strict=False)
    assert [(c.x, c.y) for c in zones.unresolved] == [(0, 0)] and len(zones.interlocks) == 1
    assert "1 that no interlock can order" in zones.line()
