"""Lion swarm (LSO) and sparrow search (SSA): roles, schedules and quality on benchmarks."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.optim.algorithms.lion import LSO
from weldplan.optim.algorithms.sparrow import SSA
from weldplan.optim.core import Context, FunctionProblem, minimize
from weldplan.optim.functions import get_function
from weldplan.optim.registry import get_optimizer


def _ctx(problem, seed=0, **budget):
    budget = {"max_iter": None, "max_evals": None, "time_budget": None, **budget}
    return Context(problem, np.random.default_rng(seed), **budget)


def _shifted_sphere(dim: int, shift: float) -> FunctionProblem:
    """Sphere with its minimum at (shift, ..., shift): both algorithms pull towards the origin."""
    return FunctionProblem(
        lambda X: np.sum((X - shift) ** 2, axis=1), [-100.0] * dim, [100.0] * dim, name="shifted"
    )


def test_lso_pride_roles():
    ctx = _ctx(get_function("sphere", 3), max_iter=5)
    opt = LSO(pop_size=30, beta=0.2)
    opt.initialize(ctx)
    assert opt._n_adult == 6  # king + 5 lionesses, 24 cubs
    with pytest.raises(ValueError):
        LSO(beta=0.5)


def test_lso_king_resamples_the_best_and_memories_are_greedy():
    problem = get_function("rastrigin", 4)
    ctx = _ctx(problem, seed=2, max_iter=20)
    opt = LSO(pop_size=12)
    opt.initialize(ctx)
    for _ in range(5):
        Pf0 = opt.Pf.copy()
        g = opt.P[np.argmin(opt.Pf)].copy()
        opt.step(ctx)
        ctx.iteration += 1
        assert np.all(opt.Pf <= Pf0)
        # the king's ||p_king - g|| = 0, so it evaluates g itself
        assert (opt.X == g).all(axis=1).any()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lso_and_ssa_reach_the_sphere_optimum(seed):
    problem = get_function("sphere", 10)
    assert minimize(problem, LSO(), max_evals=15000, rng=seed).f < 1e-6
    assert minimize(problem, SSA(), max_evals=15000, rng=seed).f < 1e-6


@pytest.mark.parametrize("name", ["lso", "ssa"])
def test_starved_budget_does_worse(name):
    problem = get_function("sphere", 10)
    full = [minimize(problem, get_optimizer(name), max_evals=15000, rng=s).f for s in range(3)]
    starved = [minimize(problem, get_optimizer(name), max_evals=300, rng=s).f for s in range(3)]
    assert min(starved) > 1e3 * max(full)


@pytest.mark.parametrize(("name", "ratio"), [("lso", 0.5), ("ssa", 1e-3)])
def test_off_origin_optimum_beats_random_search(name, ratio):
    """Both updates pull towards the origin (LSO's ``p (1 + alpha gamma)`` scales coordinates,
    SSA's producers shrink them); off it they must still beat random search. LSO does so only
    by a few times at this budget (see the module docstring of lion.py), SSA by far."""
    problem = _shifted_sphere(10, 37.0)
    ours = [minimize(problem, get_optimizer(name), max_evals=15000, rng=s).f for s in range(3)]
    rand = [minimize(problem, get_optimizer("random"), max_evals=15000, rng=s).f for s in range(3)]
    assert np.median(ours) < ratio * np.median(rand)


def test_ssa_roles_and_evaluations_per_iteration():
    problem = get_function("sphere", 5)
    ctx = _ctx(problem, seed=1, max_iter=10)
    opt = SSA(pop_size=30)
    opt.initialize(ctx)
    n0 = ctx.n_eval
    opt.step(ctx)
    # 6 producers + 24 scroungers + 3 scouts
    assert ctx.n_eval - n0 == 6 + 24 + 3
    np.testing.assert_allclose(opt.F, problem.evaluate(opt.X))
    np.testing.assert_allclose(opt.Pf, problem.evaluate(opt.P))
