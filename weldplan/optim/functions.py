"""Classic benchmark functions, vectorised over the population, as :class:`Problem` objects.

The first five are 002 Table 1 (Sphere, Schwefel 2.22, Schwefel 2.21, Rastrigin, Ackley; 30-d,
bounds as printed there); Rosenbrock and Griewank are the usual companions (Yao, Liu & Lin 1999,
functions f5 and f11, with their usual bounds). Each takes ``X (n_pop, n_var)`` and returns
``(n_pop,)``; all are minimised.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import WeldplanError
from weldplan.optim.core import Problem

log = logging.getLogger(__name__)

Array = NDArray[np.float64]


def sphere(X: Array) -> Array:
    """``sum x_i^2``; minimum 0 at the origin."""
    return np.einsum("ij,ij->i", X, X)


def schwefel_2_22(X: Array) -> Array:
    """``sum |x_i| + prod |x_i|``; minimum 0 at the origin."""
    A = np.abs(X)
    return A.sum(axis=1) + A.prod(axis=1)


def schwefel_2_21(X: Array) -> Array:
    """``max |x_i|``; minimum 0 at the origin."""
    return np.abs(X).max(axis=1)


def rastrigin(X: Array) -> Array:
    """``sum (x_i^2 - 10 cos(2 pi x_i) + 10)``; minimum 0 at the origin."""
    return (X * X - 10.0 * np.cos(2.0 * np.pi * X) + 10.0).sum(axis=1)


def ackley(X: Array) -> Array:
    """``-20 exp(-0.2 sqrt(mean x^2)) - exp(mean cos 2 pi x) + 20 + e``; minimum 0 at the origin.

    In float64 the value at the origin is ``4.44e-16``, the figure 002 Table 2 reports.
    """
    n = X.shape[1]
    s1 = np.einsum("ij,ij->i", X, X) / n
    s2 = np.cos(2.0 * np.pi * X).sum(axis=1) / n
    return -20.0 * np.exp(-0.2 * np.sqrt(s1)) - np.exp(s2) + 20.0 + math.e


def rosenbrock(X: Array) -> Array:
    """``sum 100 (x_{i+1} - x_i^2)^2 + (x_i - 1)^2``; minimum 0 at ``(1, ..., 1)``."""
    a, b = X[:, :-1], X[:, 1:]
    return (100.0 * (b - a * a) ** 2 + (a - 1.0) ** 2).sum(axis=1)


def griewank(X: Array) -> Array:
    """``sum x_i^2 / 4000 - prod cos(x_i / sqrt(i)) + 1``; minimum 0 at the origin."""
    i = np.sqrt(np.arange(1, X.shape[1] + 1, dtype=np.float64))
    return np.einsum("ij,ij->i", X, X) / 4000.0 - np.cos(X / i).prod(axis=1) + 1.0


@dataclass(frozen=True)
class FunctionSpec:
    """A benchmark function: its code, symmetric bound ``[-bound, bound]`` per variable, optimum."""

    func: Callable[[Array], Array]
    bound: float
    optimum_value: float
    optimum_coord: float  # every coordinate of the minimiser takes this value
    source: str


#: name -> spec; 002 Table 1 first (bounds as printed there), then the classic extras
FUNCTIONS: dict[str, FunctionSpec] = {
    "sphere": FunctionSpec(sphere, 100.0, 0.0, 0.0, "002 Table 1"),
    "schwefel_2_22": FunctionSpec(schwefel_2_22, 10.0, 0.0, 0.0, "002 Table 1"),
    "schwefel_2_21": FunctionSpec(schwefel_2_21, 100.0, 0.0, 0.0, "002 Table 1"),
    "rastrigin": FunctionSpec(rastrigin, 5.12, 0.0, 0.0, "002 Table 1"),
    "ackley": FunctionSpec(ackley, 32.0, 0.0, 0.0, "002 Table 1"),
    "rosenbrock": FunctionSpec(rosenbrock, 30.0, 0.0, 1.0, "Yao et al. 1999 f5"),
    "griewank": FunctionSpec(griewank, 600.0, 0.0, 0.0, "Yao et al. 1999 f11"),
}

#: the five functions of 002 Table 1/2
TABLE1: tuple[str, ...] = ("sphere", "schwefel_2_22", "schwefel_2_21", "rastrigin", "ackley")


class BenchmarkProblem(Problem):
    """A benchmark function in ``dim`` variables with its known optimum, optionally shifted.

    Parameters
    ----------
    name, dim
        Key of :data:`FUNCTIONS` and number of variables.
    shift
        Optional ``(dim,)`` (or scalar) offset ``s``: the problem becomes ``f(x - s)`` on the same
        box, so the optimum moves away from the centre. Algorithms whose moves contract towards
        the origin (SMA's ``vc * X``, pinhole opposition) look far better on the unshifted
        functions; the shift shows that gap honestly.

    Attributes
    ----------
    optimum_value
        The global minimum value.
    optimum_x
        ``(dim,) float``: a global minimiser.
    """

    def __init__(self, name: str, dim: int, shift: ArrayLike | None = None) -> None:
        spec = FUNCTIONS[name]
        lo, hi = np.full(dim, -spec.bound), np.full(dim, spec.bound)
        s = np.zeros(dim) if shift is None else np.broadcast_to(np.asarray(shift, float), (dim,))
        x = np.full(dim, spec.optimum_coord) + s
        if np.any(x < lo) or np.any(x > hi):
            raise WeldplanError(
                f"{name}: shift moves the optimum outside [{-spec.bound}, {spec.bound}]"
            )
        super().__init__(lo, hi, name=name if shift is None else f"{name}-shifted")
        self.func = spec.func
        self.optimum_value = spec.optimum_value
        self.shift = None if shift is None else s.copy()
        x.setflags(write=False)
        self.optimum_x = x

    def _evaluate(self, X: Array) -> Array:
        return self.func(X if self.shift is None else X - self.shift)


def get_function(name: str, dim: int = 30, shift: ArrayLike | None = None) -> BenchmarkProblem:
    """The benchmark ``name`` (see :data:`FUNCTIONS`) as a Problem in ``dim`` variables.

    ``shift`` moves the optimum by that offset (see :class:`BenchmarkProblem`).
    """
    key = name.lower().replace(".", "_").replace("-", "_").replace(" ", "_")
    if key not in FUNCTIONS:
        raise WeldplanError(f"unknown function '{name}'; choose one of: {', '.join(FUNCTIONS)}")
    if dim < 2:
        raise WeldplanError(f"benchmark functions need dim >= 2, got {dim}")
    return BenchmarkProblem(key, int(dim), shift=shift)
