"""``--cost time`` (weldplan.robot.route.legtime, the PairPlanning cost hook): bounds and orders."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import trimesh

from weldplan.errors import ConfigError
from weldplan.io.joints import Joints
from weldplan.robot.program import pair_time, time_route
from weldplan.robot.route import LegTimes, rest_to_rest_bound, time_stats
from weldplan.weld.cell import build_cell
from weldplan.weld.pipeline import PlanConfig, plan_route

#: the KR 150 R3100-2's URDF velocities (rad/s) and twice them as accelerations
V = np.array([1.832595715, 1.8675023, 1.989675347, 3.316125579, 3.141592654, 4.537856055])
A = 2.0 * V


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rest_to_rest_bound_is_below_every_timed_leg(seed):
    """Random joint paths of 2-6 waypoints (seeded): toppra's time of the path from rest to rest
    is never below the bound of its end points, nor is the synchronised straight move's."""
    rng = np.random.default_rng(seed)
    for _ in range(15):
        n = int(rng.integers(2, 7))
        q = np.cumsum(rng.normal(0.0, 0.4, (n, 6)), axis=0)
        lb = float(rest_to_rest_bound(q[-1] - q[0], V, A))
        assert lb > 0
        assert time_route(q, V, A, weld_rows=[0, n - 1]).total >= lb
        assert float(pair_time(q[-1] - q[0], V, A)) >= lb - 1e-12


@pytest.mark.parametrize("delta, joint", [(0.9, 0), (0.05, 3), (2.5, 5)])
def test_rest_to_rest_bound_is_the_closed_form_for_one_joint(delta, joint):
    dq = np.zeros(6)
    dq[joint] = -delta
    v, a = V[joint], A[joint]
    exact = delta / v + v / a if delta >= v * v / a else 2.0 * math.sqrt(delta / a)
    assert float(rest_to_rest_bound(dq, V, A)) == pytest.approx(exact, rel=1e-12)


def test_rest_to_rest_bound_refuses_bad_limits():
    with pytest.raises(ConfigError):
        rest_to_rest_bound(np.ones(6), V, np.zeros(6))


def _line_cell(n=6, step=60.0):
    plate = trimesh.creation.box(extents=[step * n + 200.0, 200.0, 2.0])
    plate.apply_translation([0.0, 0.0, -1.0])
    x = (np.arange(n) - (n - 1) / 2) * step
    xyz = np.c_[x, np.zeros(n), np.zeros(n)]
    ids = tuple(f"w{k}" for k in range(n))
    return build_cell(plate, Joints(ids=ids, xyz=xyz, directions=np.tile([0, 0, 1.0], (n, 1))))


def _brute(M):
    n = len(M)
    return min(
        sum(M[a, b] for a, b in itertools.pairwise(o)) for o in itertools.permutations(range(n))
    )


def test_the_cost_hook_orders_by_the_given_matrix_and_keeps_lengths_in_mm():
    """A made-up leg cost that makes the line's neighbours expensive: the route is the
    brute-force optimum over it, and its length figures stay the route's millimetres."""
    cell = _line_cell(n=6)
    ids = tuple(str(i) for i in cell.joints.ids)
    k = np.arange(6)
    M = 1.0 + 5.0 * (np.abs(k[:, None] - k[None]) == 1)  # neighbours cost 6, others 1
    np.fill_diagonal(M, 0.0)
    config = PlanConfig(sequencer="exact")
    by_len = plan_route(cell, config=config, rng=0)
    by_cost = plan_route(cell, config=config, rng=0, leg_cost=M)
    o = [ids.index(j) for j in by_cost.order]
    assert sum(M[a, b] for a, b in itertools.pairwise(o)) == pytest.approx(_brute(M))
    assert _brute(M) == pytest.approx(5.0)  # the case is one where the orders differ
    ol = [ids.index(j) for j in by_len.order]
    assert sum(M[a, b] for a, b in itertools.pairwise(ol)) > 5.0
    assert by_cost.length > by_len.length  # the price in mm, stated in mm
    assert by_cost.stats["bound_planned"] <= by_len.length + 1e-9
    with pytest.raises(ConfigError, match="leg_cost"):
        plan_route(cell, config=config, rng=0, leg_cost=M[:5, :5])


def test_time_stats_bound_is_the_held_karp_of_the_bound_matrix():
    rng = np.random.default_rng(3)
    n = 6
    B = rng.uniform(0.2, 1.0, (n, n))
    B = (B + B.T) / 2
    np.fill_diagonal(B, 0.0)
    legs = LegTimes(B + 0.1 * (1 - np.eye(n)), B, 0.5, np.ones(n, bool), 0)
    ids = tuple(f"j{k}" for k in range(n))
    st = time_stats(legs, ids, ids)
    assert st["time_bound"] == pytest.approx(_brute(B) + 0.5 * n)
    assert st["time_cost"] == pytest.approx(legs.order_time(range(n)))
    assert st["time_cost"] >= st["time_bound"]


# ----------------------------------------------------------------- with the shared robot
def _spin_station():
    """Six welds 60 mm apart on a line in front of the shared KUKA, the TCP pointing down,
    the gun alternately turned by 150 deg about its axis: neighbours on the line are close in
    mm and far in time (A6 turns 150 deg), every other weld is the reverse."""
    from scipy.spatial.transform import Rotation

    from tests.robot_fixtures import gun_tcp, shared_robot
    from weldplan.robot.route import leg_times, weld_configurations

    robot = shared_robot()
    Tft, _ = gun_tcp(robot)
    cell = _line_cell(n=6)
    T = np.tile(np.eye(4), (6, 1, 1))
    for k in range(6):
        spin = Rotation.from_euler("z", 150.0 * (k % 2), degrees=True).as_matrix()
        T[k, :3, :3] = np.diag([1.0, -1.0, -1.0]) @ spin
        T[k, :3, 3] = cell.joints.xyz[k]
    configs = weld_configurations(robot, T @ np.linalg.inv(Tft))
    return robot, cell, configs, leg_times(configs, robot.velocity, robot.acceleration,
                                           weld_time=0.5)  # fmt: skip


def _timed_cycle(robot, configs, order):
    """Toppra over the welds in ``order``: the configurations chosen by the robot route's own
    branch choice (weldplan.robot.route.configs), a rest at every weld."""
    from weldplan.robot.route import choose_configurations

    o = np.asarray(order)
    ch = choose_configurations(configs.q[o], configs.branch[o], configs.valid[o], robot.velocity)
    q = configs.q[o, ch]
    return time_route(q, robot.velocity, robot.acceleration, weld_rows=np.arange(len(o)),
                      weld_time=0.5).total  # fmt: skip


def test_cost_time_beats_cost_length_on_the_timed_cycle():
    robot, cell, configs, legs = _spin_station()
    assert configs.served.all()
    ids = tuple(str(i) for i in cell.joints.ids)
    config = PlanConfig(sequencer="exact")
    by_len = plan_route(cell, config=config, rng=0)
    by_time = plan_route(cell, config=config, rng=0, leg_cost=legs.cost)
    o_len = [ids.index(j) for j in by_len.order]
    o_time = [ids.index(j) for j in by_time.order]
    # the exact answer over the sequencer's cost, by brute force over the 720 orders
    assert legs.order_time(o_time) == pytest.approx(_brute(legs.cost) + 6 * 0.5)
    assert o_len in (list(range(6)), list(range(5, -1, -1)))
    assert legs.order_time(o_len) > legs.order_time(o_time) + 1.0
    t_len = _timed_cycle(robot, configs, o_len)
    t_time = _timed_cycle(robot, configs, o_time)
    assert t_time < t_len
    st = time_stats(legs, ids, by_time.order)
    # the proved bound sits below both timed cycles, in the same unit (s)
    assert st["time_bound"] <= t_time and st["time_bound"] <= t_len
    assert st["time_bound"] <= st["time_cost"]


def test_leg_times_are_the_least_bound_over_configurations_pair_by_pair():
    """Random configuration sets (seeded) against a plain double loop; a weld without any
    configuration costs 0 s to and from it; ``cost`` (station branch) is never below ``bound``."""
    from weldplan.robot.route import WeldConfigurations, leg_times

    rng = np.random.default_rng(5)
    n, K = 5, 6
    Q = rng.uniform(-2.0, 2.0, (n, K, 6))
    branch = rng.integers(0, 2, (n, K))
    valid = rng.random((n, K)) < 0.6
    valid[3] = False
    legs = leg_times(WeldConfigurations(Q, branch, valid), V, A, weld_time=0.3)
    for i in range(n):
        for j in range(n):
            pairs = [
                float(rest_to_rest_bound(Q[j, b] - Q[i, a], V, A))
                for a in np.flatnonzero(valid[i])
                for b in np.flatnonzero(valid[j])
            ]
            want = 0.0 if i == j or not pairs else min(pairs)
            assert legs.bound[i, j] == pytest.approx(want, abs=1e-12)
    assert np.all(legs.cost >= legs.bound - 1e-12)
    assert not legs.served[3] and legs.order_time([3, 0]) == pytest.approx(0.3)
