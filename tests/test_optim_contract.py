"""The contract every registered optimiser honours (STYLE rule 16), parametrised over the registry.

Written against the registry only, so algorithms added later are covered automatically.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from weldplan.optim.core import Problem, minimize
from weldplan.optim.functions import rastrigin
from weldplan.optim.registry import available, get_optimizer

DIM = 5
ITERS = 15


class Watched(Problem):
    """Shifted Rastrigin on an asymmetric box that records every row it is asked to evaluate."""

    def __init__(self, nan_region: bool = False) -> None:
        super().__init__(np.linspace(-5.0, -1.0, DIM), np.linspace(2.0, 8.0, DIM), name="watched")
        self.shift = np.linspace(0.3, 1.7, DIM)
        self.nan_region = nan_region
        self.rows = 0
        self.below = 0
        self.above = 0
        self.bad_shape = 0

    def _evaluate(self, X: np.ndarray) -> np.ndarray:
        if X.ndim != 2 or X.shape[1] != DIM or not np.all(np.isfinite(X)):
            self.bad_shape += 1
        self.rows += X.shape[0]
        self.below += int(np.sum(X < self.lower))
        self.above += int(np.sum(X > self.upper))
        f = rastrigin(X - self.shift)
        if self.nan_region:
            f = np.where(X[:, 0] > 0.5, np.nan, f)
        return f


def run(name: str, seed: int, **budget: int):  # type: ignore[no-untyped-def]
    p = Watched()
    return p, minimize(p, get_optimizer(name), rng=seed, **(budget or {"max_iter": ITERS}))


@pytest.fixture(params=available())
def name(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def test_same_seed_identical_result(name: str) -> None:
    _, a = run(name, 11)
    _, b = run(name, 11)
    assert a.x == b.x and a.f == b.f and a.history == b.history and a.n_eval == b.n_eval


def test_different_seeds_differ(name: str) -> None:
    _, a = run(name, 1)
    _, b = run(name, 2)
    assert a.x != b.x


def test_generator_passed_through(name: str) -> None:
    _, a = run(name, 5)
    p = Watched()
    b = minimize(p, get_optimizer(name), rng=np.random.default_rng(5), max_iter=ITERS)
    assert a.x == b.x


def test_bounds_respected_and_result_consistent(name: str) -> None:
    p, r = run(name, 3)
    assert p.below == 0 and p.above == 0 and p.bad_shape == 0
    assert r.n_eval == p.rows
    x = r.x_array
    assert np.all(x >= p.lower) and np.all(x <= p.upper)
    assert r.f == pytest.approx(p.evaluate(x[None])[0], rel=1e-12, abs=1e-12)
    assert r.n_iter == ITERS and len(r.history) == ITERS + 1
    assert all(b <= a for a, b in zip(r.history, r.history[1:], strict=False))
    assert r.f == r.history[-1]


@pytest.mark.parametrize("budget", [1, 37, 401])
def test_eval_budget_honoured_exactly(name: str, budget: int) -> None:
    p, r = run(name, 4, max_evals=budget)
    assert r.n_eval == budget == p.rows
    assert math.isfinite(r.f)


def test_problem_not_mutated(name: str) -> None:
    p = Watched()
    before = copy.deepcopy(
        {k: v for k, v in vars(p).items() if k not in ("rows", "below", "above")}
    )
    minimize(p, get_optimizer(name), rng=0, max_iter=ITERS)
    after = {k: v for k, v in vars(p).items() if k not in ("rows", "below", "above")}
    assert before.keys() == after.keys()
    for k, v in before.items():
        np.testing.assert_array_equal(after[k], v)


def test_nan_fitness_handled(name: str) -> None:
    p = Watched(nan_region=True)
    r = minimize(p, get_optimizer(name), rng=0, max_iter=ITERS)
    assert math.isfinite(r.f)
    assert r.x[0] <= 0.5


def test_params_are_settings_and_rebuild_the_optimizer(name: str) -> None:
    _, r = run(name, 0)
    assert r.params == get_optimizer(name).params()
    assert get_optimizer(name, **r.params).params() == r.params


def test_optimizer_instance_reusable(name: str) -> None:
    opt = get_optimizer(name)
    a = minimize(Watched(), opt, rng=9, max_iter=ITERS)
    b = minimize(Watched(), opt, rng=9, max_iter=ITERS)
    assert a.x == b.x


def test_small_population(name: str) -> None:
    p = Watched()
    r = minimize(p, get_optimizer(name, pop_size=4), rng=0, max_iter=5)
    assert p.below == 0 and p.above == 0 and math.isfinite(r.f)
