"""The papers' path encodings as Problems: decoding, fitness, and optimisers planning on them."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from weldplan.optim.core import Context, Optimizer, minimize
from weldplan.optim.registry import available, get_optimizer
from weldplan.planar.encodings import (
    GridPathProblem,
    SegmentPathProblem,
    SplinePathProblem,
    line_bounds,
    make_problem,
    population_diversity,
)
from weldplan.planar.exact import astar_grid
from weldplan.planar.scenarios import load_scenario, scenario_from_dict


class LocalSearch(Optimizer):
    """A tiny (1+lambda) search for the tests, independent of the optimiser family."""

    name = "test-local"

    def initialize(self, ctx: Context) -> None:
        X = ctx.rng.uniform(ctx.lower, ctx.upper, (self.pop_size, ctx.n_var))
        F = ctx.evaluate(X)
        self.x, self.f = X[np.argmin(F)], float(np.min(F))
        self.sigma = 0.2 * (ctx.upper - ctx.lower)

    def step(self, ctx: Context) -> None:
        X = self.x + ctx.rng.normal(size=(self.pop_size, ctx.n_var)) * self.sigma
        X = np.clip(X, ctx.lower, ctx.upper)
        F = ctx.evaluate(X)
        i = int(np.argmin(F))
        if F[i] < self.f:
            self.x, self.f = X[i], float(F[i])
        else:
            self.sigma = self.sigma * 0.85


@pytest.fixture(scope="module")
def circles1():
    return load_scenario("circles-1")


PROBLEMS = [
    ("circles-1", "spline", {}),
    ("map20-1", "segments", {}),
    ("map20-4", "segments", {"frame": "original"}),
    ("grid20", "grid", {}),
]


@pytest.mark.parametrize("name, enc, params", PROBLEMS)
def test_every_encoding_decodes_start_to_goal(name: str, enc: str, params: dict) -> None:
    sc = load_scenario(name)
    prob = make_problem(sc, enc, **params)
    X = np.random.default_rng(0).uniform(prob.lower, prob.upper, (7, prob.n_var))
    paths = prob.decode(X)
    assert paths.shape[0] == 7 and paths.shape[2] == 2
    np.testing.assert_allclose(paths[:, 0], np.broadcast_to(sc.start, (7, 2)), atol=0.5)
    np.testing.assert_allclose(paths[:, -1], np.broadcast_to(sc.goal, (7, 2)), atol=0.5)
    b = sc.bounds
    if enc != "spline":  # a spline may overshoot its nodes; the frame penalty handles it
        assert np.all((paths >= b[:2] - 1e-9) & (paths <= b[2:] + 1e-9))
    F = prob.evaluate(X)
    assert F.shape == (7,) and np.all(np.isfinite(F))
    m = prob.measure(X[0])
    assert m.length > 0 and m.n_points >= 2


def test_spline_fitness_is_eq10(circles1) -> None:
    prob = SplinePathProblem(circles1)
    # nodes on the straight line: length is the distance; the line cuts two circles
    nodes = np.linspace(circles1.start, circles1.goal, 5)[1:-1].reshape(1, -1)
    path = prob.decode(nodes)[0]
    L = np.linalg.norm(circles1.goal - circles1.start)
    f2 = np.mean(circles1.world.penetration(path).sum(axis=-1))
    assert f2 > 0
    assert prob.evaluate(nodes)[0] == pytest.approx(L + 1000 * f2)
    assert not prob.success(nodes)[0] and not prob.strict_success(nodes)[0]


def test_segment_bounds_follow_the_map_and_fitness_separates_feasible() -> None:
    lo, hi = line_bounds([0, 0, 20, 20], [[10, 10], [1, 1]], np.array([-1, 1]) / np.sqrt(2))
    np.testing.assert_allclose(lo, [-10 * np.sqrt(2), -np.sqrt(2)])
    np.testing.assert_allclose(hi, [10 * np.sqrt(2), np.sqrt(2)])
    sc = load_scenario("map20-1")
    prob = SegmentPathProblem(sc)
    assert prob.n_var == 12 and prob.n_segments == 13
    rng = np.random.default_rng(1)
    # smooth random offsets: a common bend plus noise, shrunk into the bounds
    bend = rng.uniform(-6, 6, (400, 1)) * np.sin(np.linspace(0, np.pi, prob.n_var + 2)[1:-1])
    X = np.clip(bend + rng.normal(0, 0.3, (400, prob.n_var)), prob.lower, prob.upper)
    F = prob.evaluate(X)
    ok = prob.success(X)
    assert ok.any() and (~ok).any()
    assert F[ok].max() < F[~ok].min()  # every feasible path beats every infeasible one
    lengths = np.array([prob.measure(x).length for x in X[ok]])
    np.testing.assert_allclose(F[ok], lengths)  # k = 0: feasible fitness is the length


def test_grid_encoding_lengths_are_octile_and_bounded_by_astar() -> None:
    sc = load_scenario("grid20")
    prob = GridPathProblem(sc)
    X = np.random.default_rng(2).uniform(prob.lower, prob.upper, (300, prob.n_var))
    F = prob.evaluate(X)
    ok = prob.success(X)
    best = astar_grid(~sc.grid.occupied, tuple(prob.s_cell), tuple(prob.g_cell)).length
    assert np.all(F[ok] >= best - 1e-9)
    for x in X[:20]:
        cells = prob.cells(x)
        steps = np.abs(np.diff(cells, axis=0))
        assert np.all(steps.max(axis=1) == 1)  # 8-connected, no repeats
        n_diag = np.sum(steps.min(axis=1) == 1)
        length = n_diag * np.sqrt(2) + (len(steps) - n_diag)
        expect = prob.evaluate(x[None])[0]
        assert length == pytest.approx(expect % prob.penalty) or expect >= prob.penalty


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 5), st.integers(0, 2**31 - 1))
def test_empty_grid_diagonal_waypoints_cost_octile(m: int, seed: int) -> None:
    data = {
        "bounds": [0, 0, 12, 12],
        "start": [0.5, 0.5],
        "goal": [11.5, 7.5],
        "obstacles": [{"type": "grid", "rows": ["." * 12] * 12}],
    }
    prob = GridPathProblem(scenario_from_dict(data), n_waypoints=m)
    best = 7 * np.sqrt(2) + 4  # octile distance of (11, 7)
    at_start = np.zeros((1, 2 * m))
    assert prob.evaluate(at_start)[0] == pytest.approx(best, abs=1e-12)
    X = np.random.default_rng(seed).uniform(prob.lower, prob.upper, (50, 2 * m))
    F = prob.evaluate(X)
    assert np.all(F >= best - 1e-9)  # the octile metric's triangle inequality
    assert np.all(F < prob.penalty)  # an empty grid: nothing blocked


def test_diversity_eq18() -> None:
    X = np.array([[0.0, 0.0], [2.0, 0.0]])
    assert population_diversity(X) == pytest.approx(np.sqrt(2.0) / 2)
    assert population_diversity(np.ones((5, 3))) == 0


def test_search_finds_collision_free_paths_and_starved_budget_is_worse(circles1) -> None:
    prob = SplinePathProblem(circles1)
    full, starved = [], []
    for seed in range(4):
        r = minimize(prob, LocalSearch(pop_size=20), max_iter=40, rng=seed)
        assert prob.success(r.x_array[None])[0]
        full.append(r.f)
        starved.append(minimize(prob, LocalSearch(pop_size=3), max_iter=1, rng=seed).f)
    assert np.mean(full) < np.mean(starved) - 0.5
    assert np.mean(full) < 1.05 * 28.884  # exact optimum of circles-1 (visibility graph)


@pytest.mark.parametrize("algorithm", available() or ["<none registered>"])
def test_each_algorithm_plans_collision_free_on_the_easiest_map(algorithm: str, circles1):
    if algorithm.startswith("<"):
        pytest.skip("no optimiser registered on this branch")
    prob = SplinePathProblem(circles1)
    if algorithm == "random":
        pytest.skip("random search is the baseline, not a planner")
    if algorithm == "woa":
        pytest.xfail(
            "WOA's best spline paths cut a circle between two samples deeper than the 0.01 "
            "graze tolerance on about half the seeds (measured 3/6 at 30 and 60 iterations)"
        )
    ok = 0
    for seed in range(3):
        r = minimize(prob, get_optimizer(algorithm, pop_size=30), max_iter=60, rng=seed)
        ok += bool(prob.success(r.x_array[None])[0])
    assert ok == 3


def test_roadmap_seeding_follows_a_free_grid_path_from_start_to_goal() -> None:
    sc = load_scenario("circles-3")
    prob = SplinePathProblem(sc)
    path = prob.roadmap_path()
    np.testing.assert_array_equal(path[0], sc.start)
    np.testing.assert_array_equal(path[-1], sc.goal)
    assert np.all(sc.world.clearance(path[1:-1]) > 0)
    steps = np.abs(np.diff(path[1:-1], axis=0))
    assert np.all(steps <= 0.25 + 1e-9)  # 8-connected moves of one 0.25 cell
    X = prob.initial_population(np.random.default_rng(0), 30)
    assert X.shape == (30, 6)
    assert np.all(X >= prob.lower) and np.all(X <= prob.upper)
    # the first ceil(30 / 3) rows lie near the roadmap path (noise of one cell), the rest do not
    nodes = X.reshape(30, 3, 2)
    d = np.min(np.linalg.norm(nodes[..., None, :] - path[None, None], axis=-1), axis=-1)
    assert np.all(d[:10] < 1.25)
    assert np.mean(d[10:] > 1.25) > 0.5


def test_lrsma_roadmap_seeding_meets_3_percent_where_the_faithful_start_does_not() -> None:
    """circles-3's optimum threads a 0.63-unit gap between two circles: from a uniform start
    LRSMA's mean is 15 % above the exact optimum (30 runs); seeded, within 3 %."""
    sc = load_scenario("circles-3")
    prob = SplinePathProblem(sc)
    exact = 29.494
    seeded, plain = [], []
    for seed in range(4):
        for init, out in (("problem", seeded), ("uniform", plain)):
            r = minimize(prob, get_optimizer("lrsma", init=init), max_iter=30, rng=seed)
            assert prob.success(r.x_array[None])[0] or init == "uniform"
            out.append(prob.measure(r.x_array).length)
    assert np.mean(seeded) < 1.03 * exact
    assert np.mean(seeded) < np.mean(plain)


@pytest.mark.slow
def test_spline_encoding_optimum_is_between_the_exact_optimum_and_a_hair_above() -> None:
    from weldplan.planar.solve import spline_encoding_optimum

    L = spline_encoding_optimum(load_scenario("circles-1"), n_jitter=0)
    assert 28.884 <= L < 1.001 * 28.884
