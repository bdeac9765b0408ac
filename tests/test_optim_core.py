"""core.py behaviour: exact budgets, NaN handling, callback stop, schedules, JSON round trip."""

from __future__ import annotations

import math

import numpy as np
import pytest

from weldplan.errors import WeldplanError
from weldplan.optim.algorithms._common import iteration_fraction
from weldplan.optim.core import Context, FunctionProblem, Optimizer, OptimizeResult, minimize
from weldplan.optim.functions import get_function
from weldplan.optim.registry import available, get_optimizer


class Counting(FunctionProblem):
    def __init__(self, func, dim: int = 3) -> None:  # type: ignore[no-untyped-def]
        super().__init__(func, -np.ones(dim), np.ones(dim), name="counting")
        self.calls = 0
        self.rows = 0

    def _evaluate(self, X):  # type: ignore[no-untyped-def]
        self.calls += 1
        self.rows += X.shape[0]
        return super()._evaluate(X)


class Fixed(Optimizer):
    """Evaluates a batch of 7 per step: budgets that are not multiples of 7 must still be exact."""

    name = "fixed"

    def initialize(self, ctx: Context) -> None:
        ctx.evaluate(ctx.rng.uniform(ctx.lower, ctx.upper, (7, ctx.n_var)))

    def step(self, ctx: Context) -> None:
        ctx.evaluate(ctx.rng.uniform(ctx.lower, ctx.upper, (7, ctx.n_var)))


def sq(X: np.ndarray) -> np.ndarray:
    return (X**2).sum(axis=1)


def test_eval_budget_is_exact() -> None:
    p = Counting(sq)
    r = minimize(p, Fixed(), max_evals=30, rng=0)
    assert r.n_eval == 30 == p.rows
    assert r.message == "evaluation or time budget spent"
    # 30 = 7 * 4 + 2: the last batch was cut to two rows
    assert p.calls == 5


def test_max_iter_history_and_monotone_best() -> None:
    r = minimize(Counting(sq), Fixed(), max_iter=6, rng=1)
    assert r.n_iter == 6 and r.n_eval == 7 * 7
    assert len(r.history) == 7
    assert all(b <= a for a, b in zip(r.history, r.history[1:], strict=False))
    assert r.f == r.history[-1] == pytest.approx(sq(r.x_array[None])[0])


def test_nan_becomes_inf_and_best_ignores_it() -> None:
    def half_nan(X: np.ndarray) -> np.ndarray:
        f = sq(X)
        f[X[:, 0] > 0] = np.nan
        return f

    r = minimize(Counting(half_nan), Fixed(), max_iter=10, rng=2)
    assert math.isfinite(r.f)
    assert r.x[0] <= 0


def test_all_nan_problem_gives_inf_not_an_error() -> None:
    def nan(X: np.ndarray) -> np.ndarray:
        return np.full(X.shape[0], np.nan)

    r = minimize(Counting(nan), Fixed(), max_iter=3, rng=0)
    assert r.f == math.inf
    assert len(r.x) == 3


def test_callback_stops_the_run() -> None:
    seen: list[int] = []

    def cb(ctx: Context) -> bool:
        seen.append(ctx.iteration)
        return ctx.iteration >= 4

    r = minimize(Counting(sq), Fixed(), max_iter=100, rng=0, callback=cb)
    assert r.n_iter == 4 and seen == [1, 2, 3, 4]
    assert r.message == "stopped by callback"


def test_time_budget_stops() -> None:
    r = minimize(Counting(sq), Fixed(), time_budget=0.05, rng=0)
    assert r.n_eval > 0 and r.message == "evaluation or time budget spent"


def test_budget_required() -> None:
    with pytest.raises(ValueError):
        minimize(Counting(sq), Fixed(), rng=0)


def test_result_json_round_trip() -> None:
    r = minimize(get_function("sphere", 4), get_optimizer("pso"), max_iter=5, rng=3)
    back = OptimizeResult.from_json(r.to_json())
    assert back == r
    assert back.seed == 3 and back.algorithm == "pso" and back.problem == "sphere"
    assert back.params["w_start"] == 0.9
    with pytest.raises(AttributeError):
        r.f = 0.0  # type: ignore[misc]


def test_per_solution_adapter_matches_vectorised() -> None:
    vec = FunctionProblem(sq, -np.ones(3), np.ones(3))
    one = FunctionProblem(lambda x: float((x**2).sum()), -np.ones(3), np.ones(3), vectorized=False)
    X = np.random.default_rng(0).uniform(-1, 1, (5, 3))
    np.testing.assert_allclose(vec.evaluate(X), one.evaluate(X))


def test_iteration_fraction_is_one_based_and_reaches_one() -> None:
    ctx = Context(
        Counting(sq), np.random.default_rng(0), max_iter=4, max_evals=None, time_budget=None
    )
    fr = []
    for it in range(4):
        ctx.iteration = it
        fr.append(iteration_fraction(ctx))
    assert fr == [0.25, 0.5, 0.75, 1.0]
    ctx = Context(
        Counting(sq), np.random.default_rng(0), max_iter=None, max_evals=100, time_budget=None
    )
    ctx.n_eval = 40
    assert iteration_fraction(ctx) == 0.4


def test_registry_names_and_errors() -> None:
    names = available()
    for n in (
        "random",
        "sma",
        "lrsma",
        "isma",
        "pso",
        "pso-w07",
        "wpso",
        "cpso",
        "mpso",
        "gwo",
        "woa",
        "aco",
    ):
        assert n in names
        assert get_optimizer(n).name == n
    assert get_optimizer("SMA", z=0.3).z == 0.3
    with pytest.raises(WeldplanError, match="unknown algorithm"):
        get_optimizer("nope")
