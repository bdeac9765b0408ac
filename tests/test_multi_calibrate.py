"""The allocation's leg times against timed programs (weldplan.multi.calibrate).

The leg-time bound (:func:`weldplan.robot.route.rest_to_rest_bound`, the per-joint bang-bang
time) is checked against toppra's timing of the same motion: equal (to toppra's grid error) on a
single-joint move, whose optimum is known in closed form, and never above it on straight and
bent joint paths. The allocate-plan loop runs on synthetic robots whose "programs" are joint
routes timed by toppra (:func:`weldplan.robot.program.time_route`): robot 0 flies every leg
through a raised via point, so its timed legs are far slower than the rest-to-rest model; the
first allocation, balanced on the model, overloads it, and the calibrated round must move welds
away and lower the timed cycle.
"""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.errors import ConfigError
from weldplan.multi import AllocationSettings, ReachMap, allocation_report
from weldplan.multi.calibrate import (
    allocate_and_plan,
    calibrated_travel,
    timed_legs,
)
from weldplan.robot.program import time_route
from weldplan.robot.route import rest_to_rest_bound

#: rad/s and rad/s^2: joint limits of a heavy six-axis arm (KR 150 class)
VEL = np.radians([105.0, 101.0, 107.0, 136.0, 129.0, 206.0])
ACC = 3.0 * VEL
#: toppra's grid makes its times a little conservative (timing.py: +1.8 % on a long walk)
GRID_SLACK = 0.03
WELD_S = 0.5


def test_single_joint_move_matches_the_bang_bang_time():
    """One joint moving ``d``: the optimum is ``d / v + v / a`` (trapezoid) or ``2 sqrt(d / a)``
    (triangle); the bound is exactly that, and toppra's timing no faster and within its grid
    error."""
    for j, d in ((0, 1.5), (2, 0.2), (5, 3.0)):
        dq = np.zeros(6)
        dq[j] = d
        v, a = VEL[j], ACC[j]
        exact = d / v + v / a if d * a >= v * v else 2.0 * np.sqrt(d / a)
        assert float(rest_to_rest_bound(dq, VEL, ACC)) == pytest.approx(exact, rel=1e-12)
        got = time_route(np.array([np.zeros(6), dq]), VEL, ACC, weld_rows=[]).total
        assert exact * (1 - 1e-6) <= got <= exact * (1 + GRID_SLACK)


def test_the_bound_is_never_above_toppra_on_straight_and_bent_paths():
    """Rest-to-rest between the two ends of a straight move, or of a path through random
    via points: the per-joint bound of the two ends is below toppra's time of the path."""
    g = np.random.default_rng(3)
    for _ in range(12):
        n = int(g.integers(2, 6))
        q = np.cumsum(g.normal(0.0, 0.6, (n, 6)), axis=0)
        got = time_route(q, VEL, ACC, weld_rows=[]).total
        assert float(rest_to_rest_bound(q[-1] - q[0], VEL, ACC)) <= got * (1 + 1e-9)


def _configs(R: int, W: int, seed: int) -> np.ndarray:
    """``(R, W, 6)`` rad: each robot's configuration at each weld."""
    return np.random.default_rng(seed).uniform(-1.2, 1.2, (R, W, 6))


def _plan(Q: np.ndarray, r: int, ids: tuple[str, ...], detour: float):
    """A plan holding a program over robot ``r``'s welds ``ids`` in that order: each leg
    through a via point raised by ``detour`` rad on joints 2 and 3 (an exact stop when
    ``detour`` > 0), timed by toppra."""
    from tests.test_multi_plan import _synthetic_plan

    qs = [Q[r, int(i)] for i in ids]
    rows, welds, stops = [qs[0]], [0], [True]
    for a, b in zip(qs[:-1], qs[1:], strict=True):
        if detour > 0:
            rows.append((a + b) / 2 + np.array([0, detour, -detour, 0, 0, 0]))
            stops.append(True)
        rows.append(b)
        welds.append(len(rows) - 1)
        stops.append(True)
    tm = time_route(np.array(rows), VEL, ACC, weld_rows=welds, stops=stops, weld_time=WELD_S)
    plan = _synthetic_plan(_Robot(), tm)
    # name the weld targets by the weld ids (the synthetic plan names them by row)
    import dataclasses

    by_row = dict(zip(welds, ids, strict=True))
    targets = tuple(
        dataclasses.replace(t, joint_id=by_row[t.row]) if t.kind == "weld" else t
        for t in plan.program.program.targets
    )
    build = dataclasses.replace(
        plan.program, program=dataclasses.replace(plan.program.program, targets=targets)
    )
    return dataclasses.replace(plan, program=build)


class _Robot:
    name = "synthetic"
    joint_names = tuple(f"j{i + 1}" for i in range(6))


def _station(W: int = 10, seed: int = 4):
    R = 2
    Q = _configs(R, W, seed)
    model = np.stack([rest_to_rest_bound(Q[r][:, None] - Q[r][None], VEL, ACC) for r in range(R)])
    reach = ReachMap.of(np.ones((R, W), bool))
    wt = np.full((R, W), WELD_S)
    return Q, model, reach, wt


def test_timed_legs_add_up_to_the_program_and_each_is_its_own_motion():
    Q, model, reach, wt = _station()
    ids = ("3", "0", "7", "5")
    p = _plan(Q, 0, ids, detour=0.8)
    tl = timed_legs(0, p.program, reach.welds)
    assert tuple(int(v) for v in tl.welds) == (3, 0, 7, 5)
    assert tl.total == pytest.approx(p.program.timing.total, abs=1e-9)
    segs = p.program.timing.segments
    # each leg is two rest-to-rest segments (weld -> via, via -> weld)
    expect = [segs[2 * k].duration + segs[2 * k + 1].duration for k in range(3)]
    assert np.allclose(tl.legs, expect, atol=1e-9)
    assert tl.head == 0.0 and tl.tail == 0.0
    assert np.all(tl.legs >= model[0][tl.welds[:-1], tl.welds[1:]] - 1e-9)


def test_calibration_replaces_the_planned_legs_both_ways_and_scales_the_rest():
    Q, model, reach, wt = _station()
    p = _plan(Q, 0, ("3", "0", "7", "5"), detour=0.8)
    tl = timed_legs(0, p.program, reach.welds)
    before = model.copy()
    travel, known, timed = calibrated_travel(model, [tl])
    assert np.array_equal(model, before)
    a, b = tl.welds[:-1], tl.welds[1:]
    assert np.allclose(travel[0, a, b], tl.legs) and np.allclose(travel[0, b, a], tl.legs)
    assert known.sum() == 2 * len(a)
    ratio = np.median(tl.legs / model[0, a, b])
    free = ~known[0]
    assert np.allclose(travel[0][free], ratio * model[0][free])
    # robot 1 not planned: its model scaled as the robot that was
    assert np.allclose(travel[1], ratio * model[1])
    with pytest.raises(ConfigError):
        calibrated_travel(model, [timed_legs(5, p.program, reach.welds)])


def _loop(rounds: int, seed: int = 0):
    Q, model, reach, wt = _station()
    settings = AllocationSettings(moves=400, kicks=5)
    detours = (0.9, 0.0)  # robot 0 flies every leg through a raised via: far slower than modelled
    return allocate_and_plan(
        lambda travel: allocation_report(reach, wt, travel, rng=seed, settings=settings),
        lambda shares: {r: _plan(Q, r, ids, detours[r]) for r, ids in shares.items()},
        model,
        rounds,
    ), model


def test_the_calibrated_round_lowers_the_timed_cycle_and_the_bound_stays_below():
    got, model = _loop(4)
    first, best = got.rounds[0], got.rounds[got.best]
    assert len(got.rounds) >= 2 and got.best >= 1
    assert best.timed_cycle < first.timed_cycle  # calibration moved welds off the slow robot
    # the first round's model cycle is far below its timed cycle; the calibrated one is closer
    assert first.model_cycle < 0.8 * first.timed_cycle
    gap = abs(best.model_cycle / best.timed_cycle - 1)
    assert gap < abs(first.model_cycle / first.timed_cycle - 1)
    # the bound over the model's rest-to-rest times bounds every timed cycle
    assert got.first.bound.value <= min(r.timed_cycle for r in got.rounds)
    assert best.timed_cycle == pytest.approx(max(p.program.timing.total for p in got.plans if p))


def test_the_loop_is_deterministic_and_budgeted():
    a, _ = _loop(2)
    b, _ = _loop(2)
    assert len(a.rounds) == 2
    assert [r.to_dict() for r in a.rounds] == [r.to_dict() for r in b.rounds]
    assert a.report.ours.assignment == b.report.ours.assignment
    one, _ = _loop(1)
    assert len(one.rounds) == 1 and one.best == 0 and one.report is one.first
    with pytest.raises(ConfigError):
        _loop(0)


def test_the_approach_term_is_the_rest_to_rest_move_to_the_lifted_pose():
    """:func:`approach_times` against forward kinematics: the configuration it times puts the
    flange exactly ``lift`` away with the same orientation, and its time is the straight
    rest-to-rest move to it; no lift, (next to) no time."""
    from tests.robot_fixtures import shared_robot
    from weldplan.multi.inputs import approach_times
    from weldplan.robot.program.timing import pair_time

    robot = shared_robot()
    q = np.array([[0.3, -1.4, 1.6, 0.2, 0.9, -0.4], [-0.5, -1.2, 1.3, -0.3, 1.1, 0.6]])
    v, a = np.asarray(robot.velocity), np.asarray(robot.acceleration)
    # no lift: the IK round trip (1e-10 rad) is all that moves
    assert np.all(approach_times(robot, q, np.zeros((2, 3)), v, a) < 1e-4)
    lift = np.array([[0.0, 0.0, 50.0], [30.0, -40.0, 0.0]])
    got = approach_times(robot, q, lift, v, a)
    T0 = robot.fk(q)
    T_lift = T0.copy()
    T_lift[:, :3, 3] += lift
    br = robot.ik_all(T_lift)
    for k in range(2):
        # the lifted configuration the term times: the solution nearest q[k]
        d = np.angle(np.exp(1j * (br.q[k] - q[k])))
        j = int(np.nanargmin(np.where(br.exists[k], np.abs(d).max(axis=1), np.inf)))
        T1 = robot.fk((q[k] + d[j])[None])[0]
        assert np.allclose(T1[:3, 3] - T0[k, :3, 3], lift[k], atol=1e-6)
        assert np.allclose(T1[:3, :3], T0[k, :3, :3], atol=1e-9)
        assert got[k] == pytest.approx(float(pair_time(d[j], v, a)), rel=1e-12)
        assert 0.0 < got[k] < 1.0


def test_the_model_adds_the_approach_at_both_ends_and_the_bound_does_not():
    from weldplan.multi.inputs import StudyInputs

    cost = np.arange(18, dtype=float).reshape(2, 3, 3)
    cost[:, [0, 1, 2], [0, 1, 2]] = 0.0
    app = np.array([[0.1, 0.2, 0.3], [1.0, 2.0, 3.0]])
    inp = StudyInputs(ReachMap.of(np.ones((2, 3), bool)), np.zeros((2, 3)), cost, cost / 2,
                      (0, 0), app)  # fmt: skip
    m = inp.model
    assert m[0, 0, 2] == pytest.approx(cost[0, 0, 2] + 0.1 + 0.3)
    assert m[1, 2, 1] == pytest.approx(cost[1, 2, 1] + 3.0 + 2.0)
    assert np.all(m[:, [0, 1, 2], [0, 1, 2]] == 0.0)
    assert np.array_equal(inp.bound, cost / 2)


def test_the_tcp_bound_is_below_toppra_for_any_configurations_of_the_two_welds():
    """The pose-free bound of :func:`weldplan.multi.bound.tcp_leg_bound` between two TCP
    positions is below toppra's time of a straight joint move between any two configurations
    that put the TCP there (random ones of the KR 150 with a gun 500 mm out), and it is the
    closed form on one lever: a single joint with lever L covering d in ``2 sqrt(d / (L a))``."""
    from tests.robot_fixtures import shared_robot
    from weldplan.multi.bound import lever_arms, tcp_leg_bound

    robot = shared_robot()
    v, a = np.asarray(robot.velocity), np.asarray(robot.acceleration)
    tcp = np.eye(4)
    tcp[2, 3] = 500.0
    L = lever_arms(robot.opw, 500.0)
    g = np.random.default_rng(5)
    lo, hi = np.asarray(robot.lower), np.asarray(robot.upper)
    for _ in range(10):
        q = g.uniform(lo, hi, (2, 6))
        p = (robot.fk(q) @ tcp)[:, :3, 3]
        T = tcp_leg_bound(p, L, v, a)
        assert T[0, 0] == 0.0 and T[0, 1] == pytest.approx(T[1, 0])
        got = time_route(q, v, a, weld_rows=[]).total
        assert 0.0 < T[0, 1] <= got
    one = tcp_leg_bound([[0, 0, 0], [10.0, 0, 0]], [1000.0], [1.0], [2.0])
    assert one[0, 1] == pytest.approx(2 * np.sqrt(10.0 / (1000.0 * 2.0)), rel=1e-9)


def test_the_lever_arms_bound_the_tcp_speed_of_the_arm():
    """Finite differences of the KR 150's forward kinematics: in random configurations, a
    joint velocity ``dq`` moves a TCP 500 mm out of the flange at most ``sum_k L_k |dq_k|``."""
    from tests.robot_fixtures import shared_robot
    from weldplan.multi.bound import lever_arms

    robot = shared_robot()
    tcp = np.eye(4)
    tcp[:3, 3] = [120.0, -60.0, 480.0]
    L = lever_arms(robot.opw, float(np.linalg.norm(tcp[:3, 3])))
    g = np.random.default_rng(6)
    q = g.uniform(robot.lower, robot.upper, (200, 6))
    eps = 1e-6
    for k in range(6):  # each joint alone: its speed times its lever arm at most
        dq = np.zeros(6)
        dq[k] = 1.0
        p0 = (robot.fk(q) @ tcp)[:, :3, 3]
        p1 = (robot.fk(q + eps * dq) @ tcp)[:, :3, 3]
        speed = np.linalg.norm(p1 - p0, axis=1) / eps
        assert speed.max() <= L[k] * (1 + 1e-6), k
        if k < 5:  # and not loose by 2x (axis 6 runs near this TCP: its arm is 134 mm)
            assert speed.max() >= 0.5 * L[k], k


def test_the_station_summary_gives_every_round():
    from weldplan.multi.station import StationPlan

    got, _ = _loop(1)
    p = StationPlan(None, 0, got.report, got.plans, rounds=got.rounds)
    rows = dict(p.summary_rows())
    c = got.rounds[0]
    assert rows["allocate-plan rounds"] == (
        f"1: model {c.model_cycle:.2f} s, timed {c.timed_cycle:.2f} s"
    )
    assert p.cycle_time == pytest.approx(c.timed_cycle)  # no schedule: the slowest program


def test_a_round_that_plans_nothing_new_ends_the_loop_with_its_calibrated_report():
    """The same shares again (here: an allocation that ignores the calibrated times): no robot
    is planned again, the timed cycle is the same, the loop stops and keeps that round, whose
    model was calibrated; it was handed the timed legs in place of the model's."""
    Q, model, reach, wt = _station()
    seen = []

    def once(travel):
        seen.append(travel)
        return allocation_report(reach, wt, model, rng=0, settings=AllocationSettings(moves=200))

    got = allocate_and_plan(
        once, lambda shares: {r: _plan(Q, r, ids, 0.5) for r, ids in shares.items()}, model, 3
    )
    assert len(got.rounds) == 2 and got.rounds[1].planned == () and got.best == 1
    assert got.rounds[1].timed_cycle == got.rounds[0].timed_cycle
    assert got.report is not got.first
    legs = timed_legs(0, got.plans[0].program, reach.welds)
    a, b = legs.welds[:-1], legs.welds[1:]
    assert np.allclose(seen[1][0, a, b], legs.legs) and np.array_equal(seen[0], model)
