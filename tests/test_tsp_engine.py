"""The fast-tsp engine: exact answers (Held-Karp, TSPLIB optima) for every variant the weld
sequencer needs, the rounding bound, clipping, the ATSP transform, infinite and avoided pairs."""

from __future__ import annotations

import os

import numpy as np
import pytest
from conftest import require_shared

from weldplan.errors import PlanningError
from weldplan.optim.discrete.costs import cost_matrix, order_cost, reduce_to_tour
from weldplan.optim.discrete.sequence import solve_sequence
from weldplan.optim.discrete.tsp_engine import (
    FINITE_MAX,
    _integers,
    choose_scale,
    fast_tsp_tour,
    search_threads,
    solve_fast_tsp,
)

pytest.importorskip("fast_tsp")


def _points(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0.0, 1000.0, size=(n, 3))


@pytest.mark.parametrize("n", [5, 12, 17])
@pytest.mark.parametrize(("first", "last"), [(None, None), (2, None), (None, 3), (1, 4)])
def test_open_paths_match_held_karp(n: int, first: int | None, last: int | None) -> None:
    C = cost_matrix(_points(n, n))
    exact = solve_sequence(C, method="exact", first=first, last=last)
    got = solve_sequence(C, method="fast-tsp", first=first, last=last, time_budget=0.3)
    eng = got.params["engine"]
    assert sorted(got.order) == list(range(n))
    if first is not None:
        assert got.order[0] == first
    if last is not None:
        assert got.order[-1] == last
    # float cost recomputed from the order, and no worse than the integer model allows
    assert got.cost == pytest.approx(order_cost(C, np.asarray(got.order), False), abs=1e-9)
    assert exact.cost <= got.cost <= exact.cost + eng["optimality_loss_bound"] + 1e-9
    assert eng["rounding_bound"] > 0  # float costs: scaled, bound reported
    assert eng["transform"] == ("symmetric" if (first, last) == (None, None) else "atsp-2n")


@pytest.mark.parametrize("closed", [False, True])
def test_asymmetric_costs_match_held_karp(closed: bool) -> None:
    rng = np.random.default_rng(7)
    C = cost_matrix(_points(11, 3)) + rng.uniform(0.0, 300.0, size=(11, 11))
    exact = solve_sequence(C, method="exact", closed=closed)
    got = solve_sequence(C, method="fast-tsp", closed=closed, time_budget=0.3)
    assert got.params["engine"]["transform"] == "atsp-2n"
    assert got.params["engine"]["feasible"]
    assert exact.cost <= got.cost <= exact.cost + got.params["engine"]["optimality_loss_bound"]


def test_integral_costs_are_exact_and_unscaled() -> None:
    C = np.rint(cost_matrix(_points(15, 1)))
    got = solve_sequence(C, method="fast-tsp", closed=True)
    eng = got.params["engine"]
    assert eng["scale"] == 1.0 and eng["rounding_bound"] == 0.0
    assert got.cost == solve_sequence(C, method="exact", closed=True).cost


@pytest.mark.parametrize(
    ("name", "optimum"),
    [("att48", 10628), ("berlin52", 7542), ("eil51", 426), ("st70", 675), ("kroA100", 21282)],
)
def test_tsplib_optimum(name: str, optimum: int) -> None:
    from weldplan.io.tsplib import read_tsplib

    D = read_tsplib(require_shared("tsplib", f"{name}.tsp")).matrix()
    got = solve_sequence(D, method="fast-tsp", closed=True, time_budget=0.5)
    assert got.cost == optimum
    assert got.params["engine"]["rounding_bound"] == 0.0


def test_rounding_bound_is_the_edge_count_over_twice_the_scale() -> None:
    C = cost_matrix(_points(30, 5))
    red = reduce_to_tour(C, False, None, None)
    res = fast_tsp_tour(red.A, red.start, seconds=0.1)
    assert res.rounding_bound == pytest.approx(red.m / (2.0 * res.scale))
    # the integer length of the returned tour is within the bound of its float length
    a, b = res.tour, np.roll(res.tour, -1)
    ints = np.minimum(np.rint(red.A[a, b] * res.scale), FINITE_MAX)
    assert abs(ints.sum() / res.scale - res.cost) <= res.rounding_bound


def test_clipping_only_where_no_tour_needs_it() -> None:
    # two clusters 100 km apart: the clusters' own edges set the scale, the two long edges of any
    # tour are clipped, so the first solve uses clipped edges and the wrapper re-solves unclipped
    P = np.vstack([_points(15, 2), _points(15, 3) + 1e5])
    C = cost_matrix(P)
    red = reduce_to_tour(C, True, None, None)
    s, cap = choose_scale(red.A, ~np.eye(red.m, dtype=bool), None)
    assert np.isfinite(cap) and cap < C.max()
    first = fast_tsp_tour(red.A, red.start, seconds=0.2)
    assert first.clipped_edges == 2
    res = solve_fast_tsp(red.A, red.start, seconds=0.2)
    assert res.clipped_edges == 0 and not np.isfinite(res.cap)
    assert res.cost <= first.cost + first.rounding_bound + res.rounding_bound


def test_infinite_pairs_are_avoided_or_reported() -> None:
    n = 12
    C = cost_matrix(_points(n, 9))
    C[0, 1:6] = C[1:6, 0] = np.inf  # node 0 reaches only 6..11
    got = solve_sequence(C, method="fast-tsp", time_budget=0.2)
    exact = solve_sequence(C, method="exact")
    assert np.isfinite(got.cost)
    assert got.cost <= exact.cost + got.params["engine"]["optimality_loss_bound"]
    assert got.params["engine"]["penalty_edges"] == 0
    C[0, 1:] = C[1:, 0] = np.inf  # node 0 reaches nothing
    with pytest.raises(PlanningError, match="no order of finite cost"):
        solve_sequence(C, method="fast-tsp", time_budget=0.2)


def test_avoided_pairs_used_only_where_needed() -> None:
    n = 40
    C = cost_matrix(_points(n, 4))
    avoid = np.zeros((n, n), dtype=bool)
    avoid[:20, :20] = True  # the first 20 nodes may not follow one another...
    np.fill_diagonal(avoid, False)
    got = solve_sequence(C, method="fast-tsp", avoid=avoid, time_budget=0.3)
    assert got.params["avoided_edges"] == 0  # ... and need not: alternate with the other 20
    o = np.asarray(got.order)
    assert not avoid[o[:-1], o[1:]].any()
    avoid[:] = True  # everything avoided: the order is the plain optimum again
    np.fill_diagonal(avoid, False)
    plain = solve_sequence(C, method="fast-tsp", avoid=avoid, time_budget=0.3)
    assert plain.params["avoided_edges"] == n - 1


def test_auto_above_held_karp_size_is_seeded_reproducible_and_close_to_the_engine() -> None:
    """``auto`` runs the seeded nearest-neighbour + polish (fast-tsp has no seed): the same
    seed gives the same order, within 3 % of fast-tsp's; with no kicks (a starved budget) the
    polish says it made none and does no better."""
    from weldplan.optim.discrete.local_search import KICKS_PER_NODE, PolishParams

    C = cost_matrix(_points(60, 6))
    a, b = solve_sequence(C, rng=4), solve_sequence(C, rng=4)
    assert a.method == "nn+polish" and a.order == b.order and a.cost == b.cost
    assert a.params["polish_stats"]["kicks"] == KICKS_PER_NODE * 61  # + the open path's dummy
    assert a.cost <= 1.03 * solve_sequence(C, method="fast-tsp").cost
    starved = solve_sequence(C, rng=4, polish_params=PolishParams(kicks=0))
    assert starved.params["polish_stats"]["kicks"] == 0 and starved.cost >= a.cost
    assert solve_sequence(C[:13, :13]).method == "exact"


@pytest.mark.parametrize("name", ["a280", "rat783", "u1060", "d1291", "u2152"])
def test_tsplib_distances_reach_the_solver_exactly(name: str) -> None:
    """fast-tsp sees TSPLIB's own ``nint`` distances, unscaled: u1060's reach 20,262 (above the
    16-bit room), so they are clipped at FINITE_MAX, far above any edge a good tour uses, rather
    than scaled by a non-integer factor that would reorder tours one unit apart."""
    from weldplan.io.tsplib import read_tsplib

    D = read_tsplib(require_shared("tsplib", f"{name}.tsp")).matrix()
    I, s, cap, exact = _integers(D, None, None)
    assert s == 1.0 and exact
    fits = D <= FINITE_MAX
    assert np.array_equal(I[fits], D[fits])
    assert (cap == FINITE_MAX) == (not fits.all())
    if not fits.all():  # each node's 10 nearest, and 4x farther, are far below the clip
        assert np.sort(D, axis=1)[:, 10].max() * 4 < FINITE_MAX


def test_integral_costs_above_the_room_are_clipped_not_scaled() -> None:
    # two clusters of 12 integer-rounded points 15.5 km apart: costs up to ~18,500 (> FINITE_MAX),
    # every node's 10 nearest within its cluster; the tour's two long edges fit below the clip
    rng = np.random.default_rng(11)
    P = np.vstack([rng.uniform(0, 1500, (12, 2)), rng.uniform(0, 1500, (12, 2)) + [15500, 0]])
    C = np.rint(cost_matrix(P))
    assert C.max() > FINITE_MAX
    assert choose_scale(C, ~np.eye(24, dtype=bool), None) == (1.0, float(FINITE_MAX))
    got = solve_sequence(C, method="fast-tsp", closed=True, time_budget=0.3)
    eng = got.params["engine"]
    assert eng["scale"] == 1.0 and eng["rounding_bound"] == 0.0 and eng["clipped_edges"] == 0
    assert got.cost == np.rint(got.cost)  # an integer length, as the solver saw it


def test_search_threads_use_every_available_core() -> None:
    assert search_threads() == len(os.sched_getaffinity(0))
    assert search_threads(1) == 1
    with pytest.raises(ValueError, match="threads"):
        search_threads(0)
    C = cost_matrix(_points(40, 8))
    red = reduce_to_tour(C, True, None, None)
    one = fast_tsp_tour(red.A, red.start, seconds=0.2, threads=1)
    assert sorted(one.tour.tolist()) == list(range(40))
    got = solve_sequence(C, method="fast-tsp", closed=True, time_budget=0.2)
    assert got.params["engine"]["threads"] == search_threads()
