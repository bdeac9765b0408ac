"""Benchmark functions: exact values at known points, optima, shapes and the shift."""

from __future__ import annotations

import math

import numpy as np
import pytest

from weldplan.errors import WeldplanError
from weldplan.optim.functions import FUNCTIONS, TABLE1, get_function


@pytest.mark.parametrize("name", list(FUNCTIONS))
def test_optimum_value_and_location(name: str) -> None:
    p = get_function(name, 7)
    f = p.evaluate(p.optimum_x[None, :])
    assert f.shape == (1,)
    assert f[0] == pytest.approx(p.optimum_value, abs=1e-15)
    # every other random point in the box is worse
    X = np.random.default_rng(0).uniform(p.lower, p.upper, (200, 7))
    assert np.all(p.evaluate(X) > p.optimum_value)


def test_table1_bounds_as_printed_in_002() -> None:
    bounds = {"sphere": 100, "schwefel_2_22": 10, "schwefel_2_21": 100, "rastrigin": 5.12}
    bounds["ackley"] = 32
    assert TABLE1 == tuple(bounds)
    for name, b in bounds.items():
        p = get_function(name)
        assert p.n_var == 30
        np.testing.assert_array_equal(p.lower, -b)
        np.testing.assert_array_equal(p.upper, b)


def test_values_by_hand() -> None:
    x = np.array([[1.0, -2.0, 0.5]])
    assert get_function("sphere", 3).evaluate(x)[0] == 5.25
    assert get_function("schwefel 2.22", 3).evaluate(x)[0] == 3.5 + 1.0
    assert get_function("Schwefel-2.21", 3).evaluate(x)[0] == 2.0
    # Rastrigin: integers sit on cos = 1, 0.5 on cos = -1
    assert get_function("rastrigin", 3).evaluate(x)[0] == pytest.approx(1 + 4 + (0.25 + 20))
    ack = -20 * math.exp(-0.2 * math.sqrt(5.25 / 3)) - math.exp((1 + 1 - 1) / 3) + 20 + math.e
    assert get_function("ackley", 3).evaluate(x)[0] == pytest.approx(ack)
    ros = 100 * (-2 - 1) ** 2 + 0 + 100 * (0.5 - 4) ** 2 + 9
    assert get_function("rosenbrock", 3).evaluate(x)[0] == pytest.approx(ros)
    gri = 5.25 / 4000 - math.cos(1) * math.cos(-2 / math.sqrt(2)) * math.cos(0.5 / math.sqrt(3)) + 1
    assert get_function("griewank", 3).evaluate(x)[0] == pytest.approx(gri)
    # the 4.44e-16 of 002 Table 2 is Ackley's float64 value at the optimum
    assert get_function("ackley", 30).evaluate(np.zeros((1, 30)))[0] == pytest.approx(
        4.44e-16, rel=1e-2
    )


def test_vectorised_rows_match_single_rows() -> None:
    rng = np.random.default_rng(1)
    for name in FUNCTIONS:
        p = get_function(name, 5)
        X = rng.uniform(p.lower, p.upper, (9, 5))
        np.testing.assert_allclose(p.evaluate(X), [p.evaluate(x)[0] for x in X])


def test_shift_moves_the_optimum() -> None:
    p = get_function("rastrigin", 4, shift=[1.0, -2.0, 0.5, 3.0])
    assert p.name == "rastrigin-shifted"
    np.testing.assert_array_equal(p.optimum_x, [1.0, -2.0, 0.5, 3.0])
    assert p.evaluate(p.optimum_x[None])[0] == 0.0
    assert p.evaluate(np.zeros((1, 4)))[0] > 0.0
    r = get_function("rosenbrock", 3, shift=2.0)
    np.testing.assert_array_equal(r.optimum_x, [3.0, 3.0, 3.0])
    with pytest.raises(WeldplanError):
        get_function("sphere", 3, shift=150.0)


def test_unknown_name_and_bad_dim() -> None:
    with pytest.raises(WeldplanError, match="unknown function"):
        get_function("himmelblau")
    with pytest.raises(WeldplanError):
        get_function("sphere", 1)
