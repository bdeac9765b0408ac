"""The weld sequencer: exact answers (brute force, Held-Karp, the paper's 15 joints), the swarm's
operators and quality, the polish, the variants and infinite costs."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from weldplan.errors import ConfigError, PlanningError
from weldplan.optim.discrete.costs import cost_matrix, order_cost, reduce_to_tour
from weldplan.optim.discrete.held_karp import held_karp_tour
from weldplan.optim.discrete.local_search import (
    PolishParams,
    local_search,
    neighbour_lists,
    polish,
    tour_cost,
)
from weldplan.optim.discrete.sequence import Sequence, SequenceSettings, solve_sequence
from weldplan.optim.discrete.tsp_pso import (
    PSOParams,
    apply_velocity,
    concat,
    difference,
    random_velocity,
    scale,
)

# Wang et al. 2017, Table 1 (mm); ids 1..15 are rows 0..14.
PAPER_JOINTS = np.array(
    [
        [1443.60, -53.20, 686.00],
        [1399.56, -60.05, 688.49],
        [1356.00, -66.67, 689.57],
        [1456.36, -48.49, 669.34],
        [1417.70, -54.51, 671.94],
        [1379.31, -60.57, 674.61],
        [1504.91, -126.99, 813.51],
        [1493.74, -109.17, 801.14],
        [1474.16, -111.25, 791.00],
        [1442.88, -117.47, 779.19],
        [1414.82, -122.26, 771.35],
        [1356.71, -132.48, 759.65],
        [1554.17, -94.37, 909.95],
        [1539.25, -99.03, 879.83],
        [1549.76, -8.79, 903.34],
    ]
)
PAPER_ORDER = (15, 13, 14, 7, 8, 9, 10, 11, 12, 3, 6, 2, 5, 1, 4)
PAPER_OPTIMUM = 595.10


def brute_force(C, closed, first, last):
    """Minimum cost over all orders (vectorised over permutations)."""
    n = C.shape[0]
    perms = np.array(list(itertools.permutations(range(n))), dtype=np.intp)
    if first is not None:
        perms = perms[perms[:, 0] == first]
    if last is not None:
        perms = perms[perms[:, -1] == last]
    cost = C[perms[:, :-1], perms[:, 1:]].sum(axis=1) if n > 1 else np.zeros(len(perms))
    if closed and n > 1:
        cost = cost + C[perms[:, -1], perms[:, 0]]
    return float(cost.min())


def random_matrix(rng, n, asymmetric, inf_fraction=0.0):
    C = rng.uniform(1.0, 100.0, size=(n, n))
    if not asymmetric:
        C = (C + C.T) / 2
    if inf_fraction:
        C[rng.random((n, n)) < inf_fraction] = np.inf
    np.fill_diagonal(C, 0.0)
    return C


VARIANTS = [
    (False, None, None),
    (True, None, None),
    (False, 0, None),
    (False, None, 1),
    (False, 2, 0),
    (True, 1, None),
    (True, None, 2),
    (True, 0, 2),
]


@pytest.mark.parametrize("closed,first,last", VARIANTS)
def test_held_karp_matches_brute_force(closed, first, last):
    rng = np.random.default_rng(7)
    for n in range(3, 9):
        for asym, inf_frac in ((False, 0.0), (True, 0.0), (True, 0.2)):
            C = random_matrix(rng, n, asym, inf_frac)
            want = brute_force(C, closed, first, last)
            if not np.isfinite(want):
                with pytest.raises(PlanningError, match="no order of finite cost exists"):
                    solve_sequence(C, method="exact", closed=closed, first=first, last=last)
                continue
            s = solve_sequence(C, method="exact", closed=closed, first=first, last=last)
            assert s.cost == pytest.approx(want, rel=1e-12)
            assert sorted(s.order) == list(range(n))
            assert order_cost(C, s.order, closed) == pytest.approx(s.cost)
            if first is not None:
                assert s.order[0] == first
            if last is not None:
                assert s.order[-1] == last


def test_tiny_instances():
    assert solve_sequence(np.zeros((1, 1))).order == (0,)
    s = solve_sequence(np.array([[0.0, 1.0], [5.0, 0.0]]))
    assert s.order == (0, 1) and s.cost == 1.0
    s = solve_sequence(np.array([[0.0, 1.0], [5.0, 0.0]]), method="pso", rng=0)
    assert s.order == (0, 1) and s.cost == 1.0


def test_paper_fifteen_joints_exact():
    C = cost_matrix(PAPER_JOINTS)
    s = solve_sequence(C)  # auto: 15 > 13 nodes -> PSO; exact below
    exact = solve_sequence(C, method="exact")
    assert exact.method == "exact"
    assert round(exact.cost, 2) == PAPER_OPTIMUM
    assert tuple(v + 1 for v in exact.order) == PAPER_ORDER
    assert s.cost == pytest.approx(exact.cost)


def test_pso_plus_polish_finds_ten_node_optimum_every_seed():
    rng = np.random.default_rng(3)
    C = cost_matrix(rng.uniform(0, 1000, size=(10, 2)))
    best = solve_sequence(C, method="exact").cost
    for seed in range(5):
        s = solve_sequence(C, method="pso", rng=seed)
        assert s.method == "pso+polish"
        assert s.cost == pytest.approx(best, rel=1e-12)
        assert s.start_cost >= s.cost


def test_same_seed_same_order_and_seeds_differ():
    C = cost_matrix(PAPER_JOINTS)
    a = solve_sequence(C, method="pso", rng=11, polish=False)
    b = solve_sequence(C, method="pso", rng=11, polish=False)
    c = solve_sequence(C, method="pso", rng=12, polish=False)
    assert a.order == b.order and a.history == b.history
    assert a.history != c.history
    assert a.seed == 11
    assert a.evaluations == 50 + 100 * 50
    assert len(a.history) == 101
    assert all(x >= y for x, y in itertools.pairwise(a.history))


def test_starved_swarm_does_measurably_worse():
    C = cost_matrix(PAPER_JOINTS)
    starved = PSOParams(iterations=2, particles=1)
    full = [solve_sequence(C, method="pso", rng=s, polish=False).cost for s in range(6)]
    weak = [
        solve_sequence(C, method="pso", rng=s, polish=False, pso=starved).cost for s in range(6)
    ]
    assert np.mean(weak) > 1.3 * np.mean(full)
    assert np.mean(full) < 1.6 * PAPER_OPTIMUM


def test_clerc_operators():
    rng = np.random.default_rng(0)
    k, P = 9, 6
    X = np.argsort(rng.random((k, P)), axis=0)
    Y = np.argsort(rng.random((k, P)), axis=0)
    d = difference(X, Y)
    assert np.array_equal(apply_velocity(Y, d), X)  # y + (x - y) = x
    assert np.all(d.length <= k - 1)
    assert np.all(difference(X, X).length == 0)
    zero = scale(np.zeros(P), d)
    assert np.array_equal(apply_velocity(Y, zero), Y)
    half = scale(np.full(P, 0.5), d)
    assert np.array_equal(half.length, d.length // 2)
    assert np.array_equal(
        apply_velocity(apply_velocity(Y, half), difference(X, apply_velocity(Y, half))), X
    )
    v = random_velocity(P, k, rng)
    w = concat(v, d)
    assert np.array_equal(w.length, v.length + d.length)
    assert np.array_equal(apply_velocity(Y, w), apply_velocity(apply_velocity(Y, v), d))
    two = scale(np.full(P, 2.0), d)
    assert np.array_equal(apply_velocity(Y, two), apply_velocity(apply_velocity(Y, d), d))


def test_descent_reaches_a_two_opt_local_optimum_and_never_worsens():
    rng = np.random.default_rng(5)
    m = 40
    C = cost_matrix(rng.uniform(0, 100, size=(m, 2)))
    t0 = rng.permutation(m)
    N = neighbour_lists(C, m)  # full lists: a true 2-opt / Or-opt local optimum
    t, c, moves = local_search(C, t0, neighbours=N)
    assert moves > 0
    assert c < tour_cost(C, t0)
    assert c == pytest.approx(tour_cost(C, t))
    assert sorted(t) == list(range(m))
    nxt = np.roll(t, -1)
    for i in range(m):
        for j in range(i + 2, m):
            if i == 0 and j == m - 1:
                continue
            delta = C[t[i], t[j]] + C[nxt[i], nxt[j]] - C[t[i], nxt[i]] - C[t[j], nxt[j]]
            assert delta > -1e-9


def test_polish_asymmetric_is_exact_about_costs():
    rng = np.random.default_rng(9)
    C = random_matrix(rng, 30, asymmetric=True)
    t0 = rng.permutation(30)
    t, c, stats = polish(C, t0, PolishParams(kicks=50), rng)
    assert c == pytest.approx(tour_cost(C, t))
    assert c < tour_cost(C, t0)
    assert stats["kicks"] == 50


@pytest.mark.slow
def test_asymmetric_twelve_nodes_heuristics_reach_exact():
    rng = np.random.default_rng(21)
    C = random_matrix(rng, 12, asymmetric=True)
    for closed, first, last in VARIANTS:
        best = solve_sequence(C, method="exact", closed=closed, first=first, last=last).cost
        for method in ("pso", "nn"):
            s = solve_sequence(C, method=method, closed=closed, first=first, last=last, rng=1)
            assert s.cost == pytest.approx(best, rel=1e-9), (method, closed, first, last)
            if first is not None:
                assert s.order[0] == first
            if last is not None:
                assert s.order[-1] == last


def test_infinite_costs_are_avoided():
    rng = np.random.default_rng(4)
    n = 25
    C = cost_matrix(rng.uniform(0, 100, size=(n, 2)))
    # forbid most pairs, keeping a Hamiltonian path 0-1-...-24 reachable
    block = rng.random((n, n)) < 0.5
    chain = np.zeros((n, n), dtype=bool)
    chain[np.arange(n - 1), np.arange(1, n)] = True
    C[block & ~chain] = np.inf
    np.fill_diagonal(C, 0.0)
    for method in ("pso", "nn"):
        s = solve_sequence(C, method=method, rng=0)
        assert np.isfinite(s.cost)


def test_no_finite_order_is_a_planning_error():
    n = 20
    C = cost_matrix(np.random.default_rng(1).uniform(0, 100, size=(n, 2)))
    C[:, 5] = np.inf  # nobody reaches node 5 ...
    C[5, 5] = 0.0
    with pytest.raises(PlanningError, match="no order of finite cost"):
        solve_sequence(C, method="pso", rng=0, first=3)  # ... and 5 cannot be first
    with pytest.raises(PlanningError, match=r"nodes no other node reaches: \[5\]"):
        solve_sequence(C, method="nn", closed=True)
    s = solve_sequence(C, method="nn", rng=0)  # an open path can start at 5
    assert s.order[0] == 5 and np.isfinite(s.cost)


def test_bad_input():
    with pytest.raises(ValueError, match="square"):
        solve_sequence(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="NaN"):
        solve_sequence(np.array([[0.0, np.nan], [1.0, 0.0]]))
    with pytest.raises(ValueError, match="unknown method"):
        solve_sequence(np.zeros((3, 3)), method="ga")
    with pytest.raises(ValueError, match="first=7"):
        solve_sequence(np.zeros((3, 3)), first=7)
    with pytest.raises(ValueError, match="same node"):
        solve_sequence(np.zeros((3, 3)), first=1, last=1)


def test_sequence_json_round_trip():
    C = cost_matrix(PAPER_JOINTS)
    s = solve_sequence(C, method="pso", rng=2, first=14)
    back = Sequence.from_json(s.to_json())
    assert back == s
    assert back.order[0] == 14


def test_reduction_round_trip():
    C = np.arange(16, dtype=float).reshape(4, 4)
    order = np.array([2, 0, 3, 1])
    for closed, first, last in ((False, None, None), (False, 2, None), (False, None, 1)):
        red = reduce_to_tour(C, closed, first, last)
        assert np.array_equal(red.to_order(red.to_tour(order)), order)
    red = reduce_to_tour(C, True, None, 3)  # closed tour, fixed last: rotated to end at 3
    assert list(red.to_order(red.to_tour(order))) == [1, 2, 0, 3]
    red = reduce_to_tour(C, True, 1, 3)  # both fixed: only the edge 3 -> 1 leaves node 3
    assert np.isinf(red.A[3, [0, 2]]).all() and red.A[3, 1] == C[3, 1]


def test_held_karp_tour_starts_at_start():
    C = cost_matrix(np.random.default_rng(2).uniform(0, 1, size=(7, 2)))
    tour, cost = held_karp_tour(C, start=4)
    assert tour[0] == 4 and sorted(tour) == list(range(7))
    assert cost == pytest.approx(tour_cost(C, tour))


def test_callback_stops_swarm_and_exact_size_guard():
    C = cost_matrix(PAPER_JOINTS)
    seen = []

    def cb(it, best):
        seen.append((it, best))
        return it >= 5

    s = solve_sequence(C, method="pso", polish=False, rng=0, callback=cb)
    assert [it for it, _ in seen] == [0, 1, 2, 3, 4, 5]
    assert len(s.history) == 6 and s.evaluations == 6 * 50
    big = cost_matrix(np.random.default_rng(0).uniform(size=(25, 2)))
    with pytest.raises(ValueError, match="at most"):
        solve_sequence(big, method="exact")
    t = solve_sequence(big, method="nn", rng=0, time_budget=0.05)  # kicks until the budget
    assert sorted(t.order) == list(range(25)) and t.method == "nn+polish"


def test_warm_start_polishes_the_given_order():
    """``initial``: no swarm, only the polish from the given order (the lazy rounds' warm start):
    never worse than the start, reaches the exact optimum on a small instance, reproducible."""
    rng = np.random.default_rng(3)
    C = cost_matrix(rng.uniform(0, 100, (12, 3)))
    best = solve_sequence(C, method="exact")
    start = rng.permutation(12)
    warm = solve_sequence(C, method="pso", initial=start, rng=1)
    assert warm.method == "warm+polish" and warm.evaluations == 0
    assert warm.start_cost == pytest.approx(order_cost(C, start, False))
    assert warm.cost <= warm.start_cost
    assert warm.cost == pytest.approx(best.cost)
    assert solve_sequence(C, method="pso", initial=start, rng=1).order == warm.order
    # from the optimum, nothing to gain
    again = solve_sequence(C, method="nn", initial=list(best.order), rng=0)
    assert again.cost == pytest.approx(best.cost)
    with pytest.raises(ValueError, match="permutation"):
        solve_sequence(C, method="pso", initial=[0, 1, 2])


def test_a_settings_object_and_its_keywords_give_the_same_order():
    rng = np.random.default_rng(11)
    C = cost_matrix(rng.uniform(0, 100, size=(25, 2)))
    st = SequenceSettings(method="pso", closed=True, first=3)
    a = solve_sequence(C, st, rng=5)
    b = solve_sequence(C, method="pso", closed=True, first=3, rng=5)
    c = solve_sequence(C, SequenceSettings(method="nn"), method="pso", closed=True, first=3, rng=5)
    assert a.order == b.order == c.order and a.order[0] == 3
    assert a.method == b.method == c.method == "pso+polish" and a.closed


def test_bad_settings_name_the_field_and_unknown_keywords_are_type_errors():
    with pytest.raises(ConfigError) as info:
        SequenceSettings(method="ga")
    assert info.value.field == "method"
    with pytest.raises(ConfigError) as info:
        SequenceSettings(time_budget="1 s")  # type: ignore[arg-type]
    assert info.value.field == "time_budget"
    with pytest.raises(TypeError, match="'clossed'"):
        solve_sequence(np.zeros((3, 3)), clossed=True)
