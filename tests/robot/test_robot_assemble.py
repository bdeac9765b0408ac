"""The walk over the served welds (:func:`weldplan.robot.route.assemble`): which welds it
keeps when detours fail. The detours here are scripted (which transfers exist is the test's
input); the geometry behind real detours is tested in test_robot_replan and test_robot_gunpath.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from weldplan.robot.placement import COLLISION, OK
from weldplan.robot.route import (
    NO_APPROACH,
    NO_TRANSFER,
    RETRACE_TRIES,
    TRANSFERS_PER_WELD,
    TRAP,
    TRAP_FAILS,
    TRAP_TESTS,
    WalkStats,
    assemble,
)


@dataclass
class _Hit:
    body: str = "link_5"
    segment: int = 0


@dataclass
class _Blocked:
    """Every route motion is blocked, except the legs leaving the weld rows in ``free``: every
    other leg between served welds needs a detour."""

    free: set[int] = field(default_factory=set)

    def path_hits(self, q, zone=None, first_only=False):
        return [] if all(int(r) in self.free for r in q[:-1, 0]) else [_Hit()]


class _Branchless:
    def branch_of(self, P):
        return np.zeros(len(P), dtype=np.int64)


@dataclass
class ScriptedDetour:
    """Each weld row ``r`` is left to (and approached from) the configuration ``q[r] + 0.5``,
    except those in ``stuck`` (no free exit); a transfer exists unless it leaves a weld in
    ``traps`` or enters one in ``pockets``."""

    q: np.ndarray
    traps: set[int] = field(default_factory=set)
    pockets: set[int] = field(default_factory=set)
    stuck: set[int] = field(default_factory=set)
    second: set[int] = field(default_factory=set)
    easy: set[int] = field(default_factory=set)
    tried: list[tuple[int, int]] = field(default_factory=list)
    ompl: dict[str, float] = field(default_factory=dict)
    robot: _Branchless = field(default_factory=_Branchless)
    checker: _Blocked = field(default_factory=_Blocked)

    def leave(self, q, row, branch):
        return None if row in self.stuck else (q + 0.5)[None]

    def retract(self, q, T, branch):
        return q + 0.5, np.zeros(3)

    retry_leg_checks: int = 4_000
    retry_total_checks: int = 8_000

    def transfer(self, qa, qb):
        a, b = int(round(qa[0] - 0.5)), int(round(qb[0] - 0.5))
        self.tried.append((a, b))
        if a in self.traps or b in self.pockets:
            return None
        return np.vstack([qa, qb])

    def joins_directly(self, qa, qb):
        """A transfer with no planner (the trial's, :meth:`transfer`'s first try): only from
        the welds in ``easy`` (as :meth:`transfer` would) or from a second way off (``q +
        0.25``, :meth:`ways_off`, which leads anywhere but into a pocket)."""
        a, b = int(np.floor(qa[0])), int(np.floor(qb[0]))
        if b in self.pockets or not (a in self.easy or qa[0] - a == 0.25):
            return None
        if a in self.traps and qa[0] - a == 0.5:
            return None
        return np.vstack([qa, qb])

    def ways_off(self, q, row, branch, first=None):
        """The first way off, and ``q + 0.25`` for the rows in ``second``."""
        first = self.leave(q, row, branch) if first is None else first
        return [first, (q + 0.25)[None]] if row in self.second else [first]

    @property
    def T_tcp(self):
        return np.tile(np.eye(4), (len(self.q), 1, 1))


def _walk(n, free=(), **kw):
    q = np.zeros((n, 6))
    q[:, 0] = np.arange(n)
    det = ScriptedDetour(q, checker=_Blocked(set(free)), **kw)
    rows = np.arange(n)
    status = [OK] * n
    detail = [""] * n
    ids = tuple(f"W{i}" for i in range(n))
    got = assemble(det, q, np.ones(n, bool), np.zeros(n, np.int64), rows, status, detail, ids)
    row, exact = got.row, got.exact
    assert np.all(np.diff(row) >= 0)  # the rows stay in route order, none twice as a weld
    assert set(range(n)) <= set(row.tolist())  # every route row has a joint row
    welded = [int(r) for r in row[exact]]
    assert len(set(welded)) == len(welded)
    assert welded == [k for k in range(n) if status[k] == OK]
    if not (det.easy or det.second):  # else some transfers need no det.transfer call
        assert got.stats.transfers == len(det.tried)
    assert max(Counter(b for _, b in det.tried).values(), default=0) <= TRANSFERS_PER_WELD
    _walk.path, _walk.zone, _walk.stats = got.q[:, 0], got.zone, got.stats
    return status, detail, welded, det, list(got.replanned)


def test_every_leg_detoured_serves_every_weld():
    status, _, welded, _, replanned = _walk(6)
    assert status == [OK] * 6 and welded == list(range(6)) and replanned == list(range(5))


def test_a_weld_whose_exit_leads_nowhere_is_left_back_along_the_path():
    # W2's exit leads nowhere: W3 is reached by going back to the end of the last transfer (W1's
    # exit, a hub) and on from there; before, W3, W4 and W5 were tried from W2 and dropped
    status, _, welded, det, replanned = _walk(6, traps={2})
    assert status == [OK] * 6 and welded == list(range(6))
    assert det.tried == [(0, 1), (1, 2), (2, 3), (1, 3), (3, 4), (4, 5)]
    at = int(np.flatnonzero(_walk.path == 2)[0])
    # W2, back to its approach (2.5) and the hub (1.5), the transfer from there to W3's
    # approach (3.5), W3
    np.testing.assert_array_equal(_walk.path[at : at + 5], [2, 2.5, 1.5, 3.5, 3])
    assert np.all(np.diff(_walk.path) != 0)  # no motion of length 0
    # each motion going back checked as it was forward (2.5 -> 2 the approach, zone exempt;
    # 1.5 -> 2.5 the transfer, whole tool), the new transfer with the whole tool
    np.testing.assert_array_equal(_walk.zone[at : at + 4], [True, False, False, True])


def test_a_weld_the_robot_cannot_go_on_from_is_dropped_not_every_weld_after_it():
    # W0 -> W1 -> W2 are the route's own free legs (no transfer, so no hub to go back to) and
    # W2's exit leads nowhere: W3 and W4 fail from W2, W2 is tested as the trap, W3 is reached
    # from W1, W2 dropped
    assert TRAP_FAILS == 2
    status, detail, welded, det, _ = _walk(6, free={0, 1}, traps={2})
    assert welded == [0, 1, 3, 4, 5]
    assert [k for k, s in enumerate(status) if s != OK] == [2]
    assert detail[2].startswith("the robot cannot go on from this weld")
    assert "W3, W4 after it" in detail[2] and "W3 reached from weld W1" in detail[2]
    assert det.tried == [(2, 3), (2, 4), (1, 3), (3, 4), (4, 5)]


def test_welds_no_one_reaches_are_dropped_and_the_weld_before_them_kept():
    # W3 and W4 cannot be entered from anywhere: each is tried from W2 and the two hubs (W1's and
    # W0's exits), W2 is tested as the trap (the trial from W1 reaches neither), kept, and the
    # walk goes on from it
    status, detail, welded, det, replanned = _walk(7, pockets={3, 4})
    assert welded == [0, 1, 2, 5, 6]
    assert [status[k] for k in (3, 4)] == [COLLISION] * 2
    assert all("on the leg from weld W2" in detail[k] for k in (3, 4))
    assert det.tried == [(0, 1), (1, 2), (2, 3), (1, 3), (0, 3), (2, 4), (1, 4), (0, 4),
                         (1, 3), (1, 4), (2, 5), (5, 6)]  # fmt: skip
    assert replanned == [0, 1, 2, 5]


def test_a_trap_whose_next_welds_no_one_reaches_is_found_on_the_next_test():
    # car2_200's case: W2's exit leads nowhere and W3, W4 cannot be entered from anywhere; the
    # first test (W3, W4 from W1) keeps W2, the second (W5, W6 from W1) reaches W5: W2 dropped
    status, detail, welded, det, _ = _walk(8, free={0, 1}, traps={2}, pockets={3, 4})
    assert welded == [0, 1, 5, 6, 7]
    assert [k for k, s in enumerate(status) if s != OK] == [2, 3, 4]
    assert "W3, W4, W5, W6 after it" in detail[2] and "W5 reached from weld W1" in detail[2]
    assert det.tried == [(2, 3), (2, 4), (1, 3), (1, 4), (2, 5), (2, 6), (1, 5), (5, 6),
                         (6, 7)]  # fmt: skip


def test_a_weld_is_tested_as_the_trap_at_most_trap_tests_times():
    # W1 is a trap and W2..W9 are pockets: W1 is tested TRAP_TESTS times (W2..W7 from W0), kept,
    # and W8..W11 are dropped from it without more tests
    assert TRAP_TESTS == 3
    status, _, welded, det, _ = _walk(12, free={0}, traps={1}, pockets=set(range(2, 10)))
    assert welded == [0, 1] and all(s == COLLISION for s in status[2:])
    assert [b for a, b in det.tried if a == 0] == [2, 3, 4, 5, 6, 7]


def test_going_back_stops_after_retrace_tries_failures_from_one_weld():
    # W3..W8 cannot be entered from anywhere: going back from W2 (to the hubs at W1's and W0's
    # exits) is tried for W3 and W4 only; later welds are tried from W2 and, in the trap
    # tests, from W1, never again from the hub at W0
    assert RETRACE_TRIES == 2
    status, _, welded, det, _ = _walk(10, pockets=set(range(3, 9)))
    assert welded == [0, 1, 2, 9]
    from_w0 = [b for a, b in det.tried if a == 0]
    assert from_w0 == [1, 3, 4]


def test_a_first_weld_the_robot_cannot_go_on_from_costs_that_weld_only():
    # W0 (no weld before it) leads nowhere: W1 and W2 fail from it, the path starts again at W1
    # (the robot may start anywhere), W2 is reached from there: W0 dropped, the rest served;
    # before, W0 stayed and every later weld was dropped from it (2/40 on a 40-spot station)
    status, detail, welded, det, _ = _walk(6, traps={0})
    assert welded == [1, 2, 3, 4, 5]
    assert [k for k, s in enumerate(status) if s != OK] == [0]
    assert detail[0].startswith("the robot cannot go on from this weld: weld(s) W1, W2 after it")
    assert "W2 reached from weld W1, the first weld without it" in detail[0]
    assert det.tried == [(0, 1), (0, 2), (1, 2), (2, 3), (3, 4), (4, 5)]
    # route row 0 held at W1's approach (1.5), where the robot starts; W1; its detour to W2
    np.testing.assert_array_equal(_walk.path[:5], [1.5, 1, 1.5, 2.5, 2])
    assert _walk.stats.trap_tests == 1 and _walk.stats.traps == 1
    assert _walk.stats.dropped == (("W0", TRAP),)


def test_a_first_weld_trap_on_free_legs_is_left_from_its_successor():
    # the route's own legs W1 -> W2 -> ... are free; W0 -> W1 is blocked and W0 leads nowhere:
    # the new start W1 needs no transfer to W2, and its head (route row 0) is W1's approach
    status, _, welded, det, _ = _walk(5, free={1, 2, 3}, traps={0})
    assert welded == [1, 2, 3, 4] and status[0] == COLLISION
    assert det.tried == [(0, 1), (0, 2)]


def test_pockets_after_the_first_weld_keep_it():
    # W1 and W2 cannot be entered from anywhere: the first weld W0 is tested (the path starts at
    # W1, W2 is not reached from it), kept, and W3 on is served from W0
    status, detail, welded, det, _ = _walk(6, pockets={1, 2})
    assert welded == [0, 3, 4, 5]
    assert [status[k] for k in (1, 2)] == [COLLISION] * 2
    assert all(detail[k].startswith("link_5 on the leg from weld W0; no transfer") for k in (1, 2))
    assert det.tried == [(0, 1), (0, 2), (1, 2), (0, 3), (3, 4), (4, 5)]
    assert _walk.path[0] == 0  # the path starts at W0 again
    s = _walk.stats
    assert (s.transfers, s.transfers_found, s.trap_tests, s.traps) == (6, 3, 1, 0)
    assert s.dropped == (("W1", NO_TRANSFER), ("W2", NO_TRANSFER))


def test_a_first_weld_trap_before_pockets_is_found_on_the_next_test():
    # W0 leads nowhere and W1, W2 cannot be entered: the first test (start at W1, W2 from it)
    # keeps W0, the second (start at W3, W4 from it) drops W0
    status, detail, welded, det, _ = _walk(7, traps={0}, pockets={1, 2})
    assert welded == [3, 4, 5, 6]
    assert [k for k, s in enumerate(status) if s != OK] == [0, 1, 2]
    assert "W1, W2, W3, W4 after it" in detail[0]
    assert det.tried == [(0, 1), (0, 2), (1, 2), (0, 3), (0, 4), (3, 4), (4, 5), (5, 6)]


def test_no_weld_gets_more_transfers_than_its_budget(monkeypatch):
    # with one transfer a weld, the trap test of W0 may not try W2 again: W0 is kept and every
    # later weld is tried once, from it
    import weldplan.robot.route.walk as asm

    monkeypatch.setattr(asm, "TRANSFERS_PER_WELD", 1)
    status, _, welded, det, _ = _walk(6, traps={0})
    assert welded == [0]
    assert det.tried == [(0, 1), (0, 2), (0, 3), (0, 4), (0, 5)]


def test_the_walk_stats_round_trip_and_name_the_welds_left_out():
    _walk(7, pockets={3, 4})
    s = _walk.stats
    assert WalkStats.from_dict(s.to_dict()) == s
    line = s.describe()
    assert line.startswith("12 transfer(s) tried (4 found, at most 7 a weld)")
    assert line.endswith("left out: 2 no transfer (W3, W4)")


def test_a_weld_with_no_way_in_is_dropped_with_that_cause_and_no_transfer():
    status, detail, welded, det, _ = _walk(5, stuck={2})
    assert welded == [0, 1, 3, 4]
    assert detail[2] == "link_5 on the leg from weld W1; weld W2 has no free gun exit or retract"
    assert det.tried == [(0, 1), (1, 3), (3, 4)]
    assert _walk.stats.dropped == (("W2", NO_APPROACH),)


def test_a_new_first_weld_with_no_way_in_is_where_the_robot_starts():
    # W0 leads nowhere and W1 has no free exit: the path starts again at W1 itself (route row 0
    # held at W1's configuration, checked with its contact zone exempt) and goes on along the
    # route's own free legs
    status, _, welded, det, _ = _walk(5, free={1, 2, 3}, traps={0}, stuck={1})
    assert welded == [1, 2, 3, 4] and status[0] == COLLISION
    assert det.tried == [(0, 2)]
    np.testing.assert_array_equal(_walk.path[:3], [1, 1, 2])
    assert _walk.zone[0]


def test_the_trial_names_the_split_legs_before_the_walk_and_shares_the_retries(caplog):
    # W2 leads nowhere (its leg to W3 split: no transfer), W4 has no way in (W3 -> W4 split at
    # its end, W4 -> W5 at its start): the trial names these three legs at once, in route order,
    # before any transfer is tried; each may take the fixed per-leg cap of OMPL retries (a
    # third of the route's would be less)
    with caplog.at_level("WARNING", logger="weldplan.robot.route.walk"):
        _walk(6, traps={2}, stuck={4}, easy={0, 1})
    s = _walk.stats
    assert s.legs_blocked == 5
    assert s.split_legs == (
        "W2 -> W3: link_5 on its own motion, no straight or tucked transfer",
        "W3 -> W4: link_5 on its own motion, no gun exit or retract at its end",
        "W4 -> W5: link_5 on its own motion, no gun exit or retract at its start",
    )
    assert s.retry_share == 4_000
    said = [r.getMessage() for r in caplog.records if "transfer trial" in r.getMessage()]
    assert len(said) == 1 and "3 of 5 leg(s) split (5 blocked, 2 joined" in said[0]
    assert WalkStats.from_dict(s.to_dict()) == s
    assert "3 of 5 blocked leg(s) split before the walk" in s.describe()


def test_one_split_leg_keeps_a_share_for_the_legs_the_trial_cannot_foresee():
    # one hard leg (W1's exit leads nowhere but W2 is reached back along the path): it shares
    # the route's retries with the legs that come after a drop or a way back (half each), while
    # a route with no split leg lets one leg take them all
    _walk(4, traps={1}, easy={0, 2})
    s = _walk.stats
    assert s.split_legs == ("W1 -> W2: link_5 on its own motion, no straight or tucked transfer",)
    assert s.retry_share == 4_000
    _walk(4, free={0, 1, 2})  # no blocked leg
    assert _walk.stats.legs_blocked == 0 and _walk.stats.split_legs == ()
    assert _walk.stats.retry_share == 8_000


def test_a_leg_whose_first_exit_leads_nowhere_is_joined_from_another_way_off():
    # W2's first way off leads nowhere, its second (2.25) joins W3 with no planner: the trial
    # finds it (no split leg), the walk takes it (no transfer tried from W2's first way, no
    # going back along the path), every weld served
    status, _, welded, det, _ = _walk(5, traps={2}, second={2}, easy={0, 1, 3})
    assert status == [OK] * 5 and welded == list(range(5))
    assert det.tried == []  # no planner asked
    at = int(np.flatnonzero(_walk.path == 2)[0])
    np.testing.assert_array_equal(_walk.path[at : at + 4], [2, 2.25, 3.5, 3])
    s = _walk.stats
    assert s.split_legs == () and s.other_ways == 1 and s.retraces == 0
    assert (s.transfers, s.transfers_found) == (4, 4)
    # without the second way W2 -> W3 is split and goes back along the path (a planner's run)
    _walk(5, traps={2}, easy={0, 1, 3})
    assert _walk.stats.split_legs == (
        "W2 -> W3: link_5 on its own motion, no straight or tucked transfer",
    )
