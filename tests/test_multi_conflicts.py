"""The allocation's conflict table (weldplan.multi.conflicts) against the independent replay,
and the allocation's charge for welds of two robots that meet (weldplan.multi.allocate.PairCost)
against every assignment of a small station."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from tests import multi_fixtures as mf
from weldplan.multi.allocate import PairCost, allocate
from weldplan.multi.problem import AllocationProblem, AllocationSettings

#: rad: each robot's A1 at its two welds (the arm stretched forward: straight ahead, and
#: turned 1.2 rad aside), and at its home (turned a quarter away)
A1 = (0.0, 1.2)
HOME_A1 = np.pi / 2


def _rested(robots):
    from weldplan.multi.conflicts import RestedRobot

    home = mf.HOME + [HOME_A1, 0, 0, 0, 0, 0]
    q = np.array([mf.HOME + [a, 0, 0, 0, 0, 0] for a in A1])
    return [RestedRobot(f"robot{k + 1}", r, home, q) for k, r in enumerate(robots)]


def _replay_meets(robots, qa, qb, clearance):
    """Whether the independent replay (own URDF FK and meshes) finds the two robots, each
    standing at one configuration, closer than ``clearance``."""
    from weldplan.multi.replay import replay_station
    from weldplan.robot.program import time_route

    timings = [
        time_route(q[None], r.velocity, r.acceleration, weld_rows=[], joint_names=r.joint_names)
        for r, q in zip(robots, (qa, qb), strict=True)
    ]
    return not replay_station(mf.replayed(robots, timings), (), clearance).ok


@pytest.mark.parametrize("distance", [3000.0, 4200.0])
def test_the_table_marks_exactly_the_rests_the_replay_finds_too_close(distance):
    from weldplan.multi.conflicts import ConflictSettings, conflict_table

    robots, _ = mf.pair(distance=distance)
    rested = _rested(robots)
    s = ConflictSettings(clearance=5.0, margin=20.0)
    table = conflict_table(rested, s)
    assert table.pair.shape == (2, 2, 2, 2) and table.at_home.shape == (2, 2, 2)
    assert np.array_equal(table.pair, table.pair.transpose(2, 3, 0, 1))  # symmetric
    assert not table.pair[0, :, 0].any() and not table.pair[1, :, 1].any()  # never itself
    for i, j in itertools.product(range(2), range(2)):
        want = _replay_meets(robots, rested[0].q[i], rested[1].q[j], table.threshold)
        assert table.pair[0, i, 1, j] == want, (i, j)
    for r, s_ in ((0, 1), (1, 0)):
        for i in range(2):
            qs = (rested[r].q[i], rested[s_].home)[:: 1 if r == 0 else -1]
            assert table.at_home[r, i, s_] == _replay_meets(robots, *qs, table.threshold)
    if distance == 3000.0:  # both arms straight ahead 3 m apart: they meet
        assert table.pair[0, 0, 1, 0] and table.fcl_calls > 0
    else:  # 4.2 m apart nothing meets, and the spheres alone prove most of it
        assert not table.pair.any() and not table.at_home.any()


def _crossing_problem():
    """Two robots, four welds on a line: robot 0 flies fast among welds 2-3 and robot 1 among
    welds 0-1, so the cheapest split gives each the welds on the other's side."""
    W = 4
    x = np.arange(W, dtype=float)
    T0 = np.abs(x[:, None] - x[None, :])
    T1 = T0.copy()
    T0[2, 3] = T0[3, 2] = 0.1
    T1[0, 1] = T1[1, 0] = 0.1
    ok = np.ones((2, W), bool)
    pair = np.zeros((2, W, 2, W), bool)
    for i, j in itertools.product((2, 3), (0, 1)):  # robot 0 right while robot 1 left: crossed
        pair[0, i, 1, j] = pair[1, j, 0, i] = True
    return ok, np.full((2, W), 1.0), np.stack([T0, T1]), pair


def _brute_force(problem, allowed):
    """The least station cycle over every assignment ``allowed`` accepts, each robot's
    share in its best order (every permutation)."""
    best = np.inf
    W = problem.ok.shape[1]
    for assign in itertools.product(range(2), repeat=W):
        a = np.array(assign)
        if not allowed(a):
            continue
        cyc = 0.0
        for r in range(2):
            w = np.flatnonzero(a == r)
            cyc = max(cyc, min((problem.cycle(r, p) for p in itertools.permutations(w)),
                               default=0.0))  # fmt: skip
        best = min(best, cyc)
    return best


def test_charging_the_pairs_that_meet_uncrosses_the_shares_at_the_best_cycle_without_them():
    ok, wt, T, pair = _crossing_problem()
    settings = AllocationSettings()
    problem = AllocationProblem.build(ok, wt, T, settings.closed)
    crossed = PairCost(pair, 10.0)
    plain = allocate(ok, wt, T, rng=0, settings=settings)
    assert crossed.count(np.array(plain.assignment)) == 4  # the cheapest split crosses
    assert plain.cycle_time == pytest.approx(_brute_force(problem, lambda a: True))
    ours = allocate(ok, wt, T, rng=0, settings=settings, conflicts=crossed)
    assert ours.stats["conflict_pairs"] == 0
    free = _brute_force(problem, lambda a: crossed.count(a) == 0)
    assert ours.cycle_time == pytest.approx(free) and free > plain.cycle_time
    # no pair charged: the same answer as without the argument
    nothing = PairCost(np.zeros_like(pair), 10.0)
    none = allocate(ok, wt, T, rng=0, settings=settings, conflicts=nothing)
    assert none.assignment == plain.assignment and none.shares == plain.shares


def test_a_conflict_is_blamed_on_the_welds_its_motions_belong_to():
    from weldplan.multi.conflicts import blamed, weld_at
    from weldplan.multi.interference import Conflict, Motion

    ids = {2: "w1", 5: "w2", 8: "w3"}  # timed rows standing on welds; 0 and 10: home
    assert weld_at(ids, 5, 5) == "w2"
    assert weld_at(ids, 0, 2) == "w1" and weld_at(ids, 10, 8) == "w3"  # home legs
    assert weld_at(ids, 6, 8) == "w3" and weld_at(ids, 6, 5) == "w2"  # between: toward the move
    assert weld_at({}, 3, 4) is None

    def motions(rows):
        out = [Motion(0, "rest", rows[0], rows[0], 0.0, 1.0)]
        for k, (a, b) in enumerate(zip(rows[:-1], rows[1:], strict=True)):
            out.append(Motion(2 * k + 1, "move", a, b, 0.0, 1.0))
            out.append(Motion(2 * k + 2, "rest", b, b, 0.0, 1.0))
        return tuple(out)

    m = (motions([0, 2, 5, 8, 10]), motions([0, 3, 6]))
    ids2 = {3: "v1"}
    got = blamed([Conflict(0, 1, 1, 4, 0.0, True), Conflict(0, 6, 1, 0, 0.0, True),
                  Conflict(0, 6, 1, 3, 0.0, True)], m, [ids, ids2])  # fmt: skip
    # robot 1 moving home -> w1 against robot 2 at rest at row 6 (its home after v1: v1's);
    # robot 1 at rest at w3 against robot 2 at its home before v1; and against robot 2
    # moving v1 -> home: the moving robot first
    assert got == [(0, "w1", 1, "v1"), (0, "w3", 1, "v1"), (1, "v1", 0, "w3")]
    assert blamed([Conflict(0, 1, 1, 0, 0.0, True)], m, [ids, None]) == [(0, "w1", 1, "")]


def test_a_blamed_weld_goes_from_the_robot_that_moved_there_to_one_that_can_take_it():
    from weldplan.multi.passes import _left_line, _repairs

    ok = np.array([[True, True, True], [True, False, True]])
    welds, names = ("a", "b", "c"), ("robot1", "robot2")
    # robot 1 at a meets robot 2 at c: a can go to robot 2
    assert list(_repairs([(0, "a", 1, "c")], ok, {}, welds, names)) == [(0, 0)]
    # robot 1 at b meets robot 2 at c: only robot 1 serves b, so robot 2 gives c away
    assert list(_repairs([(0, "b", 1, "c")], ok, {}, welds, names)) == [(1, 2)]
    # c already kept from robot 1: nothing left to move, the conflict is named instead
    assert _repairs([(0, "b", 1, "c")], ok, {(0, 2): "kept"}, welds, names) == {}
    assert _left_line([(0, "b", 1, "")], names) == "robot1 at b / robot2 at home"


def test_a_share_with_no_plan_keeps_its_welds_from_that_robot_with_the_pipelines_words():
    """A robot's share the single-robot pipeline cannot plan (``ShareFailed``, raised in a
    worker and read back in the parent) costs that robot those welds: each is kept from it
    with the pipeline's words, so the allocation gives it to another robot or lists it
    unreached with them."""
    import pickle
    from types import SimpleNamespace

    from weldplan.multi.allocate import allocate
    from weldplan.multi.conflicts import without
    from weldplan.multi.passes import _share_failed
    from weldplan.multi.problem import ReachMap
    from weldplan.multi.shares import ShareFailed

    exc = pickle.loads(pickle.dumps(ShareFailed(1, ("b", "c"), "no home leg for weld b")))
    assert (exc.k, exc.welds) == (1, ("b", "c")) and str(exc).startswith("robot 2: no home leg")
    ok = np.array([[True, False, True], [True, True, True]])
    reach = ReachMap(welds=("a", "b", "c"), robots=("robot1", "robot2"), ok=ok,
                     reasons=(("", "out of reach", ""), ("", "", "")),
                     positions=np.zeros((3, 3)))  # fmt: skip
    ctx = SimpleNamespace(inp=SimpleNamespace(reach=reach))
    forbid = _share_failed(exc, ctx, {(1, 2): "kept before"})
    assert forbid == {(1, 1): "its share had no plan: no home leg for weld b"}
    kept = without(reach, {(1, 2): "kept before", **forbid})
    assert not kept.ok[1, 1] and kept.reasons[1][1] == forbid[(1, 1)]
    T = np.ones((2, 3, 3))
    a = allocate(kept.ok, np.full((2, 3), 0.5), T, rng=0, settings=AllocationSettings())
    # the allocation names welds by column: b (1) no robot serves now, c (2) goes to robot 1
    assert [u.weld for u in a.unreached] == ["1"]
    assert "2" in a.welds_of(0) and "2" not in a.welds_of(1)
