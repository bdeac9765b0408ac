"""Shared maths of the metaheuristic family: free functions on arrays that take ``rng``.

Levy flights, chaotic maps, roulette selection, bound repair and opposition learning are used by
several papers (000 LRSMA, 001 HAFSA, 002 ISMA, 003 ParaPA); they live here once (STYLE rule 6)
rather than as methods on an optimiser base class. Every function is vectorised over the
population; none keeps state. The names and signatures below are a contract other modules code
against: keep them stable.
"""

from __future__ import annotations

import logging
import math
from functools import lru_cache
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

log = logging.getLogger(__name__)

__all__ = [
    "CHAOS_EPS",
    "LOGISTIC_MU",
    "SINGER_MU",
    "chaotic_population",
    "chaotic_sequence",
    "clip_to_bounds",
    "greedy_select",
    "levy_mantegna",
    "mantegna_sigma",
    "opposition_pinhole",
    "random_in_bounds",
    "rank_weights",
    "roulette",
]

#: Default logistic-map control parameter (003 ParaPA / CPSO: fully chaotic regime, mu = 4).
LOGISTIC_MU = 4.0
#: Default Singer-map control parameter (002 ISMA eq. 7: eta = 1.069).
SINGER_MU = 1.069
#: Chaotic iterates are kept in ``[CHAOS_EPS, 1 - CHAOS_EPS]`` so a float orbit that lands on 0
#: or 1 (absorbing for the logistic map) escapes instead of freezing the rest of the sequence.
CHAOS_EPS = 1e-12
# Seeds this close to a fixed point or a short periodic orbit are redrawn.
_FIXED_POINT_TOL = 1e-3


def mantegna_sigma(beta: float = 1.5) -> float:
    """Standard deviation of the numerator in Mantegna's algorithm.

    ``sigma_u = [Gamma(1 + beta) sin(pi beta / 2) / (Gamma((1 + beta) / 2) beta 2^((beta - 1) / 2))]
    ^ (1 / beta)`` (Mantegna 1994; 000 eq. 7; 001 eq. 12).
    """
    if not 0.0 < beta <= 2.0:
        raise ValueError(f"Levy index beta must lie in (0, 2], got {beta}")
    num = math.gamma(1.0 + beta) * math.sin(math.pi * beta / 2.0)
    den = math.gamma((1.0 + beta) / 2.0) * beta * 2.0 ** ((beta - 1.0) / 2.0)
    return float((num / den) ** (1.0 / beta))


def levy_mantegna(
    rng: np.random.Generator, size: int | tuple[int, ...], beta: float = 1.5
) -> NDArray[np.float64]:
    """Levy-stable steps of index ``beta`` by Mantegna's algorithm.

    ``step = u / |v|^(1/beta)`` with ``u ~ N(0, sigma_u^2)`` and ``v ~ N(0, 1)``, sigma_u from
    :func:`mantegna_sigma`. Symmetric, heavy-tailed (tail ``~ |s|^-(1+beta)``), unscaled: callers
    multiply by their paper's step factor.

    Parameters
    ----------
    rng
        Generator (the only source of randomness).
    size
        Output shape, e.g. ``(n_pop, n_var)``.
    beta
        Stability index in ``(0, 2]``; 1.5 is the value of 000 and 001.

    Returns
    -------
    ndarray of ``size`` float
    """
    sigma_u = mantegna_sigma(beta)
    u = rng.normal(0.0, sigma_u, size)
    v = rng.normal(0.0, 1.0, size)
    return u / np.abs(v) ** (1.0 / beta)


def _logistic(x: NDArray[np.float64], mu: float) -> NDArray[np.float64]:
    return mu * x * (1.0 - x)


def _singer(x: NDArray[np.float64], mu: float) -> NDArray[np.float64]:
    x2 = x * x
    return mu * (7.86 * x - 23.31 * x2 + 28.75 * x2 * x - 13.302875 * x2 * x2)


_MAPS = {"logistic": (_logistic, LOGISTIC_MU), "singer": (_singer, SINGER_MU)}


@lru_cache(maxsize=16)
def _bad_seeds(map_name: str, mu: float) -> NDArray[np.float64]:
    """Seeds to avoid on [0, 1]: fixed points, period-2 points, and their first preimages."""
    fn = _MAPS[map_name][0]
    grid = np.linspace(0.0, 1.0, 100001)
    bad = [0.0, 1.0]
    for k in (1, 2):
        y = grid.copy()
        for _ in range(k):
            y = fn(y, mu)
        g = y - grid
        idx = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]
        bad.extend(grid[idx].tolist())
    targets = np.asarray(bad)
    y1 = fn(grid, mu)
    near = np.min(np.abs(y1[:, None] - targets[None, :]), axis=1) < 1e-4
    bad.extend(grid[near | (y1 <= 0.0) | (y1 >= 1.0)].tolist())
    out = np.unique(np.asarray(bad))
    out.setflags(write=False)
    return out


def chaotic_sequence(
    rng: np.random.Generator,
    n_pop: int,
    n_var: int,
    map: Literal["logistic", "singer"] = "logistic",
    mu: float | None = None,
) -> NDArray[np.float64]:
    """A chaotic sequence down the population axis, one independent orbit per dimension.

    Logistic: ``x_{k+1} = mu x_k (1 - x_k)``, ``mu = 4`` by default (003 CPSO / ParaPA).
    Singer: ``x_{k+1} = mu (7.86 x - 23.31 x^2 + 28.75 x^3 - 13.302875 x^4)``, ``mu = 1.069``
    (002 ISMA eq. 7). Row 0 is a random seed ``x_0 ~ U(0, 1)`` per dimension, redrawn when it
    lies within 1e-3 of a fixed point or period-2 orbit of the map (or of a point that maps to
    0 or 1); row ``k`` is the ``k``-th iterate.

    Deviation: iterates are clipped to ``[CHAOS_EPS, 1 - CHAOS_EPS]`` so the sequence stays in
    the open interval (0, 1) even when floating-point rounding lands on 0 or 1.

    Returns
    -------
    ``(n_pop, n_var)`` float in ``(0, 1)``
    """
    if map not in _MAPS:
        raise ValueError(f"unknown chaotic map '{map}'; choose logistic or singer")
    fn, mu_default = _MAPS[map]
    mu = mu_default if mu is None else float(mu)
    bad = _bad_seeds(map, mu)
    x = rng.uniform(0.0, 1.0, n_var)
    for _ in range(100):
        near = np.min(np.abs(x[:, None] - bad[None, :]), axis=1) < _FIXED_POINT_TOL
        if not near.any():
            break
        x[near] = rng.uniform(0.0, 1.0, int(near.sum()))
    out = np.empty((n_pop, n_var))
    for k in range(n_pop):
        out[k] = x
        x = np.clip(fn(x, mu), CHAOS_EPS, 1.0 - CHAOS_EPS)
    return out


def chaotic_population(
    rng: np.random.Generator,
    lower: ArrayLike,
    upper: ArrayLike,
    n_pop: int,
    map: Literal["logistic", "singer"] = "logistic",
    mu: float | None = None,
) -> NDArray[np.float64]:
    """Initial population ``lower + c (upper - lower)`` with ``c`` from :func:`chaotic_sequence`.

    Returns
    -------
    ``(n_pop, n_var)`` float within the bounds
    """
    lo = np.asarray(lower, dtype=np.float64)
    hi = np.asarray(upper, dtype=np.float64)
    c = chaotic_sequence(rng, n_pop, lo.shape[0], map=map, mu=mu)
    return lo + c * (hi - lo)


def roulette(
    rng: np.random.Generator, weights: ArrayLike, size: int | tuple[int, ...] | None = None
) -> int | NDArray[np.intp]:
    """Indices drawn with probability proportional to ``weights (n,)``.

    Non-finite weights count as 0; when every weight is 0 (or non-finite) the draw is uniform.
    Negative weights are an error (callers turn fitness into non-negative weights first, e.g.
    ABC's ``1 / (1 + f)``).

    Returns
    -------
    int when ``size`` is None, else int array of ``size``
    """
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.size == 0:
        raise ValueError("roulette needs at least one weight")
    w = np.where(np.isfinite(w), w, 0.0)
    if np.any(w < 0):
        raise ValueError("roulette weights must be non-negative")
    total = w.sum()
    if not np.isfinite(total) or total <= 0.0:
        w = np.ones_like(w)
        total = float(w.size)
    cdf = np.cumsum(w)
    r = rng.random(size) * cdf[-1]
    idx = np.searchsorted(cdf, r, side="right")
    idx = np.minimum(idx, w.size - 1)
    if size is None:
        return int(idx)
    return idx.astype(np.intp)


def clip_to_bounds(X: ArrayLike, lower: ArrayLike, upper: ArrayLike) -> NDArray[np.float64]:
    """``np.clip(X, lower, upper)`` as a new float array (bounds broadcast along the last axis)."""
    return np.clip(np.asarray(X, dtype=np.float64), lower, upper)


def random_in_bounds(
    rng: np.random.Generator, lower: ArrayLike, upper: ArrayLike, n: int
) -> NDArray[np.float64]:
    """``n`` points uniform in the box: ``(n, n_var)`` float."""
    lo = np.asarray(lower, dtype=np.float64)
    hi = np.asarray(upper, dtype=np.float64)
    return lo + rng.random((n, lo.shape[0])) * (hi - lo)


def opposition_pinhole(
    x: ArrayLike, lower: ArrayLike, upper: ArrayLike, k: float | ArrayLike
) -> NDArray[np.float64]:
    """Pinhole-imaging opposite point (002 ISMA eq. 8).

    ``x* = (a + b) / 2 + (a + b) / (2 k) - x / k`` with ``a, b`` the lower and upper bounds and
    ``k`` the scale factor of the pinhole image; ``k = 1`` gives classic opposition ``a + b - x``.
    Broadcasts over ``x`` (any shape ending in ``n_var``); the result is not clipped.
    """
    x = np.asarray(x, dtype=np.float64)
    s = np.asarray(lower, dtype=np.float64) + np.asarray(upper, dtype=np.float64)
    k = np.asarray(k, dtype=np.float64)
    return s / 2.0 + s / (2.0 * k) - x / k


def rank_weights(F: ArrayLike) -> NDArray[np.float64]:
    """Normalised fitness ranks in ``[0, 1]``: 0 for the best (lowest) value, 1 for the worst.

    Ties get the rank of their first occurrence in sorted order (stable sort); one solution gets 0.
    """
    F = np.asarray(F, dtype=np.float64).reshape(-1)
    n = F.shape[0]
    ranks = np.empty(n)
    ranks[np.argsort(F, kind="stable")] = np.arange(n)
    return ranks / max(n - 1, 1)


def greedy_select(
    X: NDArray[np.float64],
    F: NDArray[np.float64],
    X_new: NDArray[np.float64],
    F_new: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Keep each new solution only where it is strictly better: returns new ``(X, F)`` arrays."""
    better = F_new < F
    return np.where(better[:, None], X_new, X), np.where(better, F_new, F)
