"""ParaPA (003): chaotic start, hosts, nectar limit, elite exchange and the cross-function hook."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.errors import ConfigError
from weldplan.optim.algorithms.parapa import ParaPA, ParaPASettings, distance_cross
from weldplan.optim.core import Context, minimize
from weldplan.optim.functions import get_function
from weldplan.optim.operators import chaotic_population


def _ctx(problem, seed=0, **budget):
    budget = {"max_iter": None, "max_evals": None, "time_budget": None, **budget}
    return Context(problem, np.random.default_rng(seed), **budget)


def test_distance_cross_is_minus_the_mean_distance():
    c = np.array([[0.0, 0.0], [3.0, 4.0]])
    e = np.array([[3.0, 4.0], [0.0, 0.0]])
    np.testing.assert_allclose(distance_cross(c, e), [-2.5, -2.5])
    np.testing.assert_allclose(distance_cross(c[:1], e[:1]), [-5.0])


def test_initial_population_is_the_logistic_chaos_and_hosts_are_its_best():
    problem = get_function("sphere", 4)
    ctx = _ctx(problem, seed=11, max_iter=10)
    opt = ParaPA(pop_size=30, n_swarms=3)
    opt.initialize(ctx)
    expected = chaotic_population(np.random.default_rng(11), problem.lower, problem.upper, 30)
    np.testing.assert_array_equal(opt.X.reshape(30, 4), expected)
    assert opt.O.shape == (3, 2, 4)  # NP / 5 hosts per swarm of 10
    for s in range(3):
        np.testing.assert_array_equal(np.sort(opt.Of[s]), np.sort(opt.F[s])[:2])


def test_cross_function_is_called_with_the_documented_shapes():
    calls = []

    def cross(candidates, elites):
        calls.append((candidates.shape, elites.shape))
        return np.zeros(candidates.shape[0])

    problem = get_function("rastrigin", 5)
    opt = ParaPA(pop_size=60, n_swarms=3, n_elites=10, n_cross=3, n_worst=3, cross=cross)
    minimize(problem, opt, max_iter=4, rng=0)
    assert len(calls) == 2 * 3 * 4  # twice per swarm per exchange, one exchange per iteration
    first, second = calls[0], calls[1]
    assert first == ((20, 5), (10, 5))  # the foreign elites of 2 swarms against own elites
    assert second == ((6, 5), (10, 5))  # 3 chosen + 3 worst memories


def test_single_swarm_never_exchanges():
    def cross(candidates, elites):  # pragma: no cover - must not run
        raise AssertionError("cross called with one swarm")

    minimize(get_function("sphere", 3), ParaPA(pop_size=20, n_swarms=1, cross=cross), max_iter=5)


def test_swarms_exchange_elites_through_the_pool():
    problem = get_function("rastrigin", 6)
    ctx = _ctx(problem, seed=3, max_iter=20)
    # a cross function that ranks every candidate equal: the first foreign elite (the best
    # memory of the next swarm in pool order) is the pool output
    opt = ParaPA(pop_size=30, n_swarms=3, cross=lambda c, e: np.zeros(c.shape[0]))
    opt.initialize(ctx)
    opt.step(ctx)
    for s in range(3):
        foreign = np.concatenate([opt.P[o] for o in range(3) if o != s])
        hit = (opt.X[s][:, None, :] == foreign[None, :, :]).all(axis=2)
        assert hit.any(), f"swarm {s} received no elite"


def test_cross_function_chooses_which_elite_enters():
    """A cross function that prefers the swarm's own memories keeps foreign elites out."""
    problem = get_function("rastrigin", 6)
    ctx = _ctx(problem, seed=3, max_iter=20)

    def prefer_own(candidates, elites):
        # with NP = n_elites = 10 the elites are the whole swarm: 0 for its own rows, else 1
        own = (candidates[:, None, :] == elites[None, :, :]).all(axis=2).any(axis=1)
        return np.where(own, 0.0, 1.0)

    opt = ParaPA(pop_size=30, n_swarms=3, n_elites=10, cross=prefer_own)
    opt.initialize(ctx)
    opt.step(ctx)
    for s in range(3):
        foreign = np.concatenate([opt.P[o] for o in range(3) if o != s])
        assert not (opt.X[s][:, None, :] == foreign[None, :, :]).all(axis=2).any()
    # and the worst particle now sits on one of its swarm's own memories
    for s in range(3):
        assert (opt.X[s][:, None, :] == opt.P[s][None, :, :]).all(axis=2).any()


def test_nectar_limit_resamples_idle_hosts():
    problem = get_function("sphere", 3)
    ctx = _ctx(problem, seed=0, max_iter=10)
    opt = ParaPA(pop_size=30, n_swarms=3, limit_factor=0.0)
    opt.initialize(ctx)
    n0 = ctx.n_eval
    opt.step(ctx)
    assert np.all(opt.trial == 0)  # limit 0: every host not improved is abandoned and reset
    assert ctx.n_eval > n0 + 30  # the abandoned hosts were re-sampled and evaluated


def test_hosts_never_get_worse_without_abandonment():
    problem = get_function("rastrigin", 4)
    ctx = _ctx(problem, seed=7, max_iter=50)
    opt = ParaPA(pop_size=30, n_swarms=3, limit_factor=1e9)
    opt.initialize(ctx)
    for _ in range(10):
        before = opt.Of.copy()
        opt.step(ctx)
        ctx.iteration += 1
        assert np.all(opt.Of <= before)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_parapa_reaches_the_sphere_optimum(seed):
    r = minimize(get_function("sphere", 10), ParaPA(pop_size=30), max_evals=30000, rng=seed)
    assert r.f < 1e-6


def test_parapa_starved_budget_does_worse():
    problem = get_function("sphere", 10)
    full = [minimize(problem, ParaPA(pop_size=30), max_evals=30000, rng=s).f for s in range(3)]
    starved = [minimize(problem, ParaPA(pop_size=30), max_evals=900, rng=s).f for s in range(3)]
    assert min(starved) > 1e3 * max(full)


def test_settings_object_and_keywords_are_one_optimiser_and_bad_fields_are_named():
    a = ParaPA(60, ParaPASettings(n_swarms=2, w_max=1))
    b = ParaPA(60, n_swarms=2, w_max=1)
    assert a.params() == b.params() and a.n_swarms == 2 and a.w_max == 1.0
    assert list(a.params())[:3] == ["pop_size", "n_swarms", "w_max"]
    with pytest.raises(ConfigError) as info:
        ParaPASettings(exchange_interval=0)
    assert info.value.field == "exchange_interval"
    with pytest.raises(ConfigError, match="pop_size >= n_swarms"):
        ParaPA(2, n_swarms=3)
    with pytest.raises(TypeError):
        ParaPA(60, n_swarm=2)
