"""The shared operators: Levy steps, chaotic maps, roulette, bounds and pinhole opposition."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from weldplan.optim import operators as op


def test_mantegna_sigma_matches_closed_form_for_beta_1_5() -> None:
    # Gamma(2.5) sin(3pi/4) / (Gamma(1.25) 1.5 2^0.25), to the power 1/1.5: the textbook 0.6966
    num = math.gamma(2.5) * math.sin(0.75 * math.pi)
    den = math.gamma(1.25) * 1.5 * 2**0.25
    assert op.mantegna_sigma(1.5) == pytest.approx((num / den) ** (1 / 1.5))
    assert op.mantegna_sigma(1.5) == pytest.approx(0.696575, abs=1e-5)
    # beta = 2 is the Gaussian limit: sigma_u^2 = Gamma(3) sin(pi) / ... = 0
    assert op.mantegna_sigma(2.0) == pytest.approx(0.0, abs=1e-7)
    with pytest.raises(ValueError):
        op.mantegna_sigma(0.0)


def test_levy_steps_are_symmetric_and_heavy_tailed() -> None:
    rng = np.random.default_rng(0)
    s = op.levy_mantegna(rng, (200_000,), beta=1.5)
    assert s.shape == (200_000,)
    assert np.all(np.isfinite(s))
    # symmetric: median near zero, as many positive as negative
    assert abs(np.median(s)) < 0.01
    assert abs(np.mean(s > 0) - 0.5) < 0.005
    # heavy tails: far more mass beyond 10 sigma_u than a Gaussian of the same scale (~1e-23)
    sigma = op.mantegna_sigma(1.5)
    assert np.mean(np.abs(s) > 10 * sigma) > 1e-3
    # the tail index of |step| is about beta: Hill estimator on the top 1 %
    a = np.sort(np.abs(s))[::-1]
    k = 2000
    hill = 1.0 / np.mean(np.log(a[:k] / a[k]))
    assert 1.2 < hill < 1.8
    # u / |v|^(1/beta): with the same rng state the formula is reproduced exactly
    r1, r2 = np.random.default_rng(5), np.random.default_rng(5)
    u = r2.normal(0.0, sigma, (3, 4))
    v = r2.normal(0.0, 1.0, (3, 4))
    np.testing.assert_array_equal(op.levy_mantegna(r1, (3, 4)), u / np.abs(v) ** (1 / 1.5))


@pytest.mark.parametrize("name", ["logistic", "singer"])
def test_chaotic_sequence_stays_in_open_unit_interval_and_is_seeded(name: str) -> None:
    c = op.chaotic_sequence(np.random.default_rng(1), 5000, 30, map=name)
    assert c.shape == (5000, 30)
    assert np.all(c > 0.0) and np.all(c < 1.0)
    same = op.chaotic_sequence(np.random.default_rng(1), 5000, 30, map=name)
    np.testing.assert_array_equal(c, same)
    other = op.chaotic_sequence(np.random.default_rng(2), 5000, 30, map=name)
    assert not np.array_equal(c, other)
    # the orbit does not freeze on a fixed point: consecutive rows keep changing
    assert np.all(np.abs(np.diff(c[-100:], axis=0)).max(axis=0) > 1e-3)
    # columns are distinct orbits
    assert len({tuple(np.round(c[:10, j], 12)) for j in range(30)}) == 30


def test_logistic_sequence_follows_the_map_and_has_the_arcsine_law() -> None:
    c = op.chaotic_sequence(np.random.default_rng(3), 400, 50, map="logistic")
    # each row is the logistic image of the previous one (until rounding, which chaos amplifies,
    # but the one-step relation holds to machine precision)
    np.testing.assert_allclose(c[1:], 4.0 * c[:-1] * (1.0 - c[:-1]), atol=1e-12)
    # invariant density of mu = 4 is 1 / (pi sqrt(x (1 - x))): arcsine distribution
    assert stats.kstest(c[50:].ravel(), stats.arcsine.cdf).statistic < 0.02


def test_singer_sequence_follows_the_map() -> None:
    c = op.chaotic_sequence(np.random.default_rng(4), 50, 10, map="singer")
    x = c[:-1]
    expected = 1.069 * (7.86 * x - 23.31 * x**2 + 28.75 * x**3 - 13.302875 * x**4)
    np.testing.assert_allclose(c[1:], np.clip(expected, op.CHAOS_EPS, 1 - op.CHAOS_EPS), atol=1e-12)


def test_chaotic_sequence_avoids_fixed_point_seeds() -> None:
    # whatever the seed, row 0 is never at the logistic fixed points 0, 0.75 or pre-image 0.25, 0.5
    for seed in range(50):
        x0 = op.chaotic_sequence(np.random.default_rng(seed), 1, 200, map="logistic")[0]
        for fp in (0.0, 0.25, 0.5, 0.75, 1.0):
            assert np.min(np.abs(x0 - fp)) >= 1e-3 * 0.999
    with pytest.raises(ValueError):
        op.chaotic_sequence(np.random.default_rng(0), 2, 2, map="tent")  # type: ignore[arg-type]


def test_chaotic_population_maps_into_bounds() -> None:
    lo, hi = np.array([-5.0, 0.0, 10.0]), np.array([5.0, 1.0, 20.0])
    X = op.chaotic_population(np.random.default_rng(0), lo, hi, 40, map="singer")
    c = op.chaotic_sequence(np.random.default_rng(0), 40, 3, map="singer")
    np.testing.assert_allclose(X, lo + c * (hi - lo))
    assert np.all(X >= lo) and np.all(X <= hi)


def test_roulette_frequencies_follow_weights() -> None:
    rng = np.random.default_rng(0)
    w = np.array([1.0, 2.0, 0.0, 7.0])
    idx = op.roulette(rng, w, size=100_000)
    freq = np.bincount(idx, minlength=4) / idx.size
    np.testing.assert_allclose(freq, w / w.sum(), atol=0.005)
    assert freq[2] == 0.0
    # chi-square goodness of fit on the non-zero cells
    counts = np.bincount(idx, minlength=4)[[0, 1, 3]]
    expected = idx.size * w[[0, 1, 3]] / w.sum()
    assert stats.chisquare(counts, expected).pvalue > 1e-3
    one = op.roulette(np.random.default_rng(1), w)
    assert isinstance(one, int) and one in (0, 1, 3)


def test_roulette_degenerate_weights_are_uniform() -> None:
    for w in (np.zeros(5), np.full(5, np.nan), np.array([np.inf, np.nan, 0.0, 0.0, 0.0])):
        idx = op.roulette(np.random.default_rng(2), w, size=50_000)
        freq = np.bincount(idx, minlength=5) / idx.size
        np.testing.assert_allclose(freq, 0.2, atol=0.01)
    # a non-finite weight counts as zero when others are positive
    idx = op.roulette(np.random.default_rng(2), np.array([np.inf, 1.0, 1.0]), size=1000)
    assert 0 not in idx
    with pytest.raises(ValueError):
        op.roulette(np.random.default_rng(0), np.array([1.0, -1.0]))


def test_bounds_helpers() -> None:
    lo, hi = np.array([-1.0, 0.0]), np.array([1.0, 10.0])
    X = np.array([[-3.0, 5.0], [0.5, 11.0]])
    Y = op.clip_to_bounds(X, lo, hi)
    np.testing.assert_array_equal(Y, [[-1.0, 5.0], [0.5, 10.0]])
    assert Y is not X and X[0, 0] == -3.0
    R = op.random_in_bounds(np.random.default_rng(0), lo, hi, 1000)
    assert R.shape == (1000, 2)
    assert np.all(R >= lo) and np.all(R <= hi)
    assert R[:, 1].max() > 9.0 and R[:, 0].min() < -0.9


def test_opposition_pinhole_formula() -> None:
    lo, hi = np.array([-100.0, 0.0]), np.array([100.0, 10.0])
    x = np.array([30.0, 2.0])
    # k = 1: classic opposition a + b - x
    np.testing.assert_allclose(op.opposition_pinhole(x, lo, hi, 1.0), lo + hi - x)
    # 002 eq. 8 by hand with k = 2: (a+b)/2 + (a+b)/4 - x/2
    np.testing.assert_allclose(op.opposition_pinhole(x, lo, hi, 2.0), [-15.0, 6.5])
    # eq. 7: (c - x) / (x* - c) = k with c the centre of the box
    c = (lo + hi) / 2
    xs = op.opposition_pinhole(x, lo, hi, 3.0)
    np.testing.assert_allclose((c - x) / (xs - c), 3.0)
    # broadcasts over a population and per-dimension k
    X = np.array([[30.0, 2.0], [0.0, 5.0]])
    out = op.opposition_pinhole(X, lo, hi, np.array([1.0, 2.0]))
    np.testing.assert_allclose(out, [[-30.0, 5.0 + 2.5 - 1.0], [0.0, 5.0 + 2.5 - 2.5]])


def test_rank_weights_and_greedy_select() -> None:
    np.testing.assert_allclose(op.rank_weights([3.0, 1.0, 2.0]), [1.0, 0.0, 0.5])
    np.testing.assert_allclose(op.rank_weights([4.0]), [0.0])
    X, F = np.zeros((3, 2)), np.array([1.0, 2.0, 3.0])
    Xn, Fn = np.ones((3, 2)), np.array([0.5, 2.0, np.inf])
    Xs, Fs = op.greedy_select(X, F, Xn, Fn)
    np.testing.assert_array_equal(Fs, [0.5, 2.0, 3.0])
    np.testing.assert_array_equal(Xs[:, 0], [1.0, 0.0, 0.0])
