"""Faithfulness of individual algorithms: the papers' formulas checked against hand computations."""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.optim.algorithms.isma import ISMA
from weldplan.optim.algorithms.lrsma import LRSMA
from weldplan.optim.algorithms.mpso import MPSO
from weldplan.optim.algorithms.pso import PSO
from weldplan.optim.algorithms.sma import SMA
from weldplan.optim.core import Context, FunctionProblem, minimize
from weldplan.optim.functions import get_function, sphere
from weldplan.optim.registry import get_optimizer


def ctx_for(problem, max_iter: int = 10, seed: int = 0) -> Context:  # type: ignore[no-untyped-def]
    return Context(
        problem, np.random.default_rng(seed), max_iter=max_iter, max_evals=None, time_budget=None
    )


def test_sma_weights_match_000_eq_4() -> None:
    sma = SMA(pop_size=4)
    sma.X = np.zeros((4, 2))
    sma.F = np.array([3.0, 1.0, 4.0, 2.0])  # ranks: 2, 0, 3, 1
    W = sma.weights(np.random.default_rng(0))
    r = np.random.default_rng(0).random((4, 2))
    bF, wF = 1.0, 4.0
    lg = np.log10((bF - np.array([1.0, 2.0, 3.0, 4.0])) / (bF - wF - np.finfo(float).eps) + 1)
    # rows of r follow the sorted order: best half gets 1 + r lg, the rest 1 - r lg
    expected_sorted = np.vstack(
        [1 + r[0] * lg[0], 1 + r[1] * lg[1], 1 - r[2] * lg[2], 1 - r[3] * lg[3]]
    )
    np.testing.assert_allclose(W[[1, 3, 0, 2]], expected_sorted)
    assert np.all(W[1] == 1.0)  # the best has lg(0 + 1) = 0
    np.testing.assert_allclose(W[2], 1 - r[3] * np.log10(2))


def test_sma_reproduces_002_table2_zero_on_sphere() -> None:
    # 002 Table 2 reports mean 0 for SMA on the 30-d Sphere with N = 30, 500 iterations
    r = minimize(get_function("sphere", 30), SMA(), max_iter=500, rng=0)
    assert r.f == 0.0
    assert SMA().z == 0.03 and LRSMA().z == 0.3


def test_lrsma_rotation_is_eq_9_as_printed() -> None:
    X = np.array([[3.0, 4.0], [0.0, 0.0]])
    rng = np.random.default_rng(7)
    out = LRSMA.rotate(rng, X, (0.1, 1.0))
    ref = np.random.default_rng(7)
    omega = ref.uniform(0.1, 1.0, 2)
    R = ref.uniform(-1.0, 1.0, (2, 2))
    shift = omega[0] * (R[0] @ X[0]) / 5.0
    np.testing.assert_allclose(out[0], X[0] + shift)  # the same scalar added to every coordinate
    np.testing.assert_array_equal(out[1], [0.0, 0.0])  # ||X|| = 0: no move


def test_lrsma_tolerance_monitor_eq_8() -> None:
    lr = LRSMA(f_min=1.0, t_max=2)
    lr.tau, lr.prev_best_f = 0, 100.0
    fired = []
    for f in [99.5, 99.2, 99.0, 98.9, 90.0, 89.9, 89.8, 89.7]:
        lr.best_f = f
        fired.append(lr._stagnating())
    # small steps: tau 1, 2, then fire (reset to 0), 1; big step resets; 1, 2, fire
    assert fired == [False, False, True, False, False, False, False, True]


def test_lrsma_metropolis_printed_vs_standard() -> None:
    # a worse elite with delta = 0 is never accepted as printed (exp(0) = 1 < rand is false)
    # and always accepted by the standard rule (rand < 1)
    p = FunctionProblem(lambda X: np.zeros(X.shape[0]), -np.ones(3), np.ones(3))
    for rule, expect_move in (("printed", False), ("standard", True)):
        lr = LRSMA(pop_size=5, metropolis=rule, p_r=0.0)
        ctx = ctx_for(p)
        lr.initialize(ctx)
        before = lr.best_x.copy()
        lr._rotate_and_anneal(ctx)
        assert (not np.array_equal(lr.best_x, before)) == expect_move


def test_isma_opposition_improves_best_dimension_wise() -> None:
    # optimum at the centre: pinhole opposition with k = 1e6 maps each coordinate to ~0
    p = get_function("sphere", 4)
    isma = ISMA(pop_size=5, k=1e6)
    ctx = ctx_for(p)
    isma.initialize(ctx)
    isma.best_x = np.array([50.0, -20.0, 10.0, 5.0])
    isma.best_f = float(sphere(isma.best_x[None])[0])
    n0 = ctx.n_eval
    isma._after_update(ctx)
    assert ctx.n_eval - n0 == 4 + 1  # D candidates plus the combination of improving ones
    np.testing.assert_allclose(isma.best_x, [-50e-6, 20e-6, -10e-6, -5e-6])


def test_isma_initial_population_is_singer_chaos() -> None:
    p = get_function("sphere", 3)
    isma = ISMA(pop_size=6)
    ctx = ctx_for(p, seed=4)
    isma.initialize(ctx)
    c = (isma.X - p.lower) / (p.upper - p.lower)
    x = c[:-1]
    nxt = 1.069 * (7.86 * x - 23.31 * x**2 + 28.75 * x**3 - 13.302875 * x**4)
    np.testing.assert_allclose(c[1:], nxt, atol=1e-9)


def test_pso_inertia_schedules() -> None:
    p = get_function("sphere", 2)
    for name, first, last in (("pso", 0.9, 0.4), ("wpso", 0.9, 0.1), ("pso-w07", 0.7, 0.7)):
        opt = get_optimizer(name)
        ctx = ctx_for(p, max_iter=10)
        ctx.iteration = 0
        w0 = opt.inertia(ctx)
        ctx.iteration = 9
        assert opt.inertia(ctx) == pytest.approx(last)
        assert w0 == pytest.approx(first - (first - last) / 10)
    assert get_optimizer("cpso").init == "logistic" and get_optimizer("cpso").c1 == 1.49445


def test_pso_velocity_clamped() -> None:
    pso = PSO(pop_size=8, v_max=0.05)
    p = get_function("sphere", 3)
    ctx = ctx_for(p)
    pso.initialize(ctx)
    for _ in range(5):
        pso.step(ctx)
        assert np.all(np.abs(pso.V) <= 0.05 * 200 + 1e-12)


def test_mpso_swarms_and_migration() -> None:
    p = get_function("sphere", 3)
    m = MPSO(pop_size=9, n_swarms=3)
    ctx = ctx_for(p)
    m.initialize(ctx)
    np.testing.assert_array_equal(np.bincount(m.swarm), [3, 3, 3])
    m.P = np.arange(27, dtype=float).reshape(9, 3)
    m.PF = np.array([5.0, 1.0, 9.0, 4.0, 8.0, 2.0, 7.0, 3.0, 6.0])
    # swarm bests: 1 (f=1), 5 (f=2), 7 (f=3); worsts: 2 (9), 4 (8), 6 (7)
    m._migrate()
    np.testing.assert_array_equal(m.PF, [5.0, 1.0, 2.0, 4.0, 1.0, 2.0, 1.0, 3.0, 6.0])
    np.testing.assert_array_equal(m.P[2], np.arange(15, 18))  # swarm 0 got swarm 1's elite
    np.testing.assert_array_equal(m.P[4], np.arange(3, 6))  # swarms 1, 2 got swarm 0's elite
    np.testing.assert_array_equal(m.X[6], np.arange(3, 6))
    m._update_guides(ctx)
    np.testing.assert_array_equal(m._guide()[m.swarm == 2][0], np.arange(3, 6))
    assert m.GF == 1.0


def test_gwo_leaders_are_three_best_ever() -> None:
    gwo = get_optimizer("gwo", pop_size=6)
    p = get_function("sphere", 2)
    ctx = ctx_for(p)
    gwo.initialize(ctx)
    seen = [gwo.F.copy()]
    for _ in range(4):
        gwo.step(ctx)
        seen.append(gwo.F.copy())
    np.testing.assert_allclose(gwo.LF, np.sort(np.concatenate(seen))[:3])


def test_acor_rank_weights_and_kernel_widths_match_socha_dorigo() -> None:
    from weldplan.optim.algorithms.acor import ACOR

    opt = ACOR(pop_size=3, archive_size=4, q=0.5, xi=0.85)
    p = FunctionProblem(sphere, np.full(2, -5.0), np.full(2, 5.0))
    ctx = ctx_for(p)
    opt.initialize(ctx)
    # eq. 4-5: w_l ~ exp(-(l - 1)^2 / (2 q^2 k^2)), normalised; q k = 2
    w = np.exp(-(np.arange(4) ** 2) / 8.0)
    np.testing.assert_allclose(opt.p, w / w.sum())
    assert np.all(np.diff(opt.F) >= 0) and opt.X.shape == (4, 2)
    # eq. 6: sigma_l = xi sum_e |s_e - s_l| / (k - 1); replay the step's draws
    X0 = opt.X.copy()
    state = ctx.rng.bit_generator.state
    opt.step(ctx)
    rng = np.random.default_rng()
    rng.bit_generator.state = state
    from weldplan.optim.operators import roulette

    g = roulette(rng, opt.p, 3)
    sigma = 0.85 * np.abs(X0[None] - X0[g][:, None]).sum(axis=1) / 3
    Y = np.clip(X0[g] + sigma * rng.standard_normal((3, 2)), -5, 5)
    allX = np.vstack([X0, Y])
    allF = sphere(allX)
    np.testing.assert_allclose(opt.X, allX[np.argsort(allF, kind="stable")[:4]])
