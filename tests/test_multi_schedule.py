"""The station's schedule under interlocks (weldplan.multi.schedule), on routes timed by toppra:
the waits and the cycle time against hand-computed answers, deadlocks, rows that are not stops."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.errors import PlanningError
from weldplan.multi.schedule import Interlock, StationSchedule, station_schedule
from weldplan.robot.program import time_route

VEL = np.full(6, 2.0)
ACC = np.full(6, 8.0)
WT = 0.5


def _timed(offset: float, n: int = 4):
    """A route of ``n`` rows, each a weld, 0.3 rad apart on joint 1."""
    q = np.zeros((n, 6))
    q[:, 0] = offset + 0.3 * np.arange(n)
    return time_route(q, VEL, ACC, weld_rows=np.arange(n), weld_time=WT)


def _check_contiguous(s: StationSchedule, r: int, end: float) -> None:
    acts = s.of(r)
    assert acts[0].start == pytest.approx(0.0, abs=1e-12)
    for a, b in zip(acts[:-1], acts[1:], strict=True):
        assert b.start == pytest.approx(a.end, abs=1e-9)
    assert acts[-1].end == pytest.approx(end, abs=1e-9)


def test_without_interlocks_each_robot_runs_its_own_timing():
    ta, tb = _timed(0.0), _timed(1.0, 3)
    s = station_schedule(["a", "b"], [ta, tb], weld_ids=[{0: "w0"}, None])
    assert s.cycle_times == pytest.approx((ta.total, tb.total))
    assert s.waiting == (0.0, 0.0)
    _check_contiguous(s, 0, ta.total)
    _check_contiguous(s, 1, tb.total)
    assert s.seconds(0, "weld") == pytest.approx(4 * WT)
    assert s.seconds(1, "move") == pytest.approx(tb.motion_time)
    assert [a.label for a in s.of(0) if a.kind == "weld"] == ["w0", "", "", ""]
    assert s.utilisation[0] == pytest.approx(1.0)


def test_an_interlock_holds_the_second_robot_until_the_first_is_ready():
    ta, tb = _timed(0.0), _timed(1.0)
    lock = Interlock("Z1", first=0, release_row=2, second=1, wait_row=0, signal=1)
    s = station_schedule(["a", "b"], [ta, tb], [lock])
    ready = ta.row_times[2] + WT  # a at rest at row 2, its weld done
    leave = tb.row_times[0] + WT  # b would leave row 0 after its weld
    wait = ready - leave
    assert wait > 0
    assert s.waiting == pytest.approx((0.0, wait))
    assert s.cycle_times[1] == pytest.approx(tb.total + wait)
    held = [a for a in s.of(1) if a.kind == "wait"]
    assert len(held) == 1 and held[0].label == "Z1_R1_R2" and held[0].end == pytest.approx(ready)
    _check_contiguous(s, 1, tb.total + wait)
    # b's next move starts when a is ready
    moves = [a for a in s.of(1) if a.kind == "move"]
    assert moves[0].start == pytest.approx(ready)
    back = StationSchedule.from_dict(s.to_dict())
    assert back.cycle_times == pytest.approx(s.cycle_times, abs=1e-6)
    assert back.interlocks == (lock,)


def test_an_interlock_already_met_costs_nothing():
    ta, tb = _timed(0.0), _timed(1.0)
    lock = Interlock("Z1", first=0, release_row=0, second=1, wait_row=3, signal=1)
    s = station_schedule(["a", "b"], [ta, tb], [lock])
    assert s.waiting == (0.0, 0.0)


def test_waits_chain_through_a_third_robot():
    t = [_timed(0.0), _timed(1.0), _timed(2.0)]
    locks = [
        Interlock("Z1", 0, 3, 1, 0, 1),  # b waits at its row 0 until a has done everything
        Interlock("Z2", 1, 1, 2, 0, 2),  # c waits at its row 0 until b is done with row 1
    ]
    s = station_schedule(["a", "b", "c"], t, locks)
    # b leaves row 0 when a is done, moves (its row gap less its dwell at 0), welds at row 1
    b_ready_1 = t[0].total + (t[1].row_times[1] - t[1].row_times[0])
    c_wait = b_ready_1 - (t[2].row_times[0] + WT)
    assert s.waiting[2] == pytest.approx(c_wait)


def test_a_circle_of_interlocks_is_a_deadlock():
    ta, tb = _timed(0.0), _timed(1.0)
    locks = [Interlock("Z1", 0, 2, 1, 1, 1), Interlock("Z2", 1, 2, 0, 1, 2)]
    with pytest.raises(PlanningError, match="deadlock"):
        station_schedule(["a", "b"], [ta, tb], locks)


def test_an_interlock_off_a_stop_row_or_on_an_idle_robot_is_refused():
    q = np.zeros((3, 6))
    q[:, 0] = [0.0, 0.2, 0.6]
    ta = time_route(q, VEL, ACC, weld_rows=[0, 2], weld_time=WT)  # row 1: a via, no stop
    tb = _timed(1.0)
    with pytest.raises(PlanningError, match="not a stop row"):
        station_schedule(["a", "b"], [ta, tb], [Interlock("Z1", 0, 1, 1, 0, 1)])
    with pytest.raises(PlanningError, match="idle"):
        station_schedule(["a", "b"], [ta, None], [Interlock("Z1", 0, 0, 1, 0, 1)])


def test_an_interlock_is_two_program_actions_named_by_route_rows():
    lock = Interlock("Z3", first=1, release_row=2, second=0, wait_row=1, signal=7)
    (r1, set_), (r0, wait) = lock.actions([np.array([0, 4, 9]), None])
    assert (r1, set_.action, set_.row, set_.signal, set_.name) == (1, "set", 2, 7, "Z3_R2_R1")
    assert (r0, wait.action, wait.row) == (0, "wait", 4)
    with pytest.raises(ValueError):
        Interlock("Z", 0, 1, 0, 1, 1)
