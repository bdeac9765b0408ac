"""The one optimiser interface: Problems, Optimizers, ``minimize`` and its result.

Every continuous metaheuristic in weldplan (the slime mould, fish swarm, PSO/ABC families and
their baselines) is an :class:`Optimizer` that sees only a :class:`Problem`. Maps, encodings and
penalties live in Problems (STYLE rule 3); populations are arrays (rule 7).

An optimiser implements two methods, each free to evaluate as many solutions as its paper's
iteration needs (AFSA's behaviours, ABC's phases, LRSMA's perturbations):

``initialize(ctx)``
    create the population and evaluate it through ``ctx.evaluate``;
``step(ctx)``
    one iteration of the paper's main loop.

``ctx.evaluate`` counts evaluations, enforces the evaluation budget exactly (rows past the budget
are not evaluated and come back as ``inf``), turns NaN fitness into ``inf`` and tracks the best
solution ever evaluated, so no optimiser has to. Schedules that depend on the iteration count
(SMA's ``a = arctanh(1 - t/T)``, a linearly falling inertia weight) read ``ctx.progress`` in
``[0, 1]``, which works for every kind of budget.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.random import RNGLike, as_generator, seed_of


class Problem:
    """A box-bounded minimisation problem evaluated a whole population at a time.

    Subclasses set ``lower`` and ``upper`` (``(n_var,) float``) and implement
    :meth:`_evaluate`. Use :class:`FunctionProblem` to wrap a plain function.
    """

    name: str = "problem"

    def __init__(self, lower: ArrayLike, upper: ArrayLike, name: str | None = None) -> None:
        lo = np.array(lower, dtype=np.float64).reshape(-1)
        hi = np.array(upper, dtype=np.float64).reshape(-1)
        if lo.shape != hi.shape:
            raise ValueError(f"bounds differ in length: {lo.shape} vs {hi.shape}")
        if np.any(~np.isfinite(lo)) or np.any(~np.isfinite(hi)) or np.any(hi < lo):
            raise ValueError("bounds must be finite with lower <= upper")
        lo.setflags(write=False)
        hi.setflags(write=False)
        self.lower = lo
        self.upper = hi
        if name is not None:
            self.name = name

    @property
    def n_var(self) -> int:
        return int(self.lower.shape[0])

    def evaluate(self, X: ArrayLike) -> NDArray[np.float64]:
        """Fitness ``(n_pop,)`` of solutions ``X (n_pop, n_var)``; lower is better."""
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        if X.shape[1] != self.n_var:
            raise ValueError(f"expected {self.n_var} variables, got shape {X.shape}")
        F = np.asarray(self._evaluate(X), dtype=np.float64).reshape(-1)
        if F.shape[0] != X.shape[0]:
            raise ValueError(f"{self.name}: evaluate returned {F.shape[0]} values for {X.shape[0]}")
        return F

    def _evaluate(self, X: NDArray[np.float64]) -> NDArray[np.float64]:  # pragma: no cover
        raise NotImplementedError


class FunctionProblem(Problem):
    """A Problem from a function.

    Parameters
    ----------
    func
        ``func(X (n_pop, n_var)) -> (n_pop,)`` when ``vectorized`` (the fast path), otherwise
        ``func(x (n_var,)) -> float`` called once per solution (the adapter for per-solution code).
    """

    def __init__(
        self,
        func: Callable[[NDArray[np.float64]], Any],
        lower: ArrayLike,
        upper: ArrayLike,
        *,
        vectorized: bool = True,
        name: str | None = None,
    ) -> None:
        super().__init__(lower, upper, name=name or getattr(func, "__name__", "function"))
        self.func = func
        self.vectorized = vectorized

    def _evaluate(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        if self.vectorized:
            return np.asarray(self.func(X), dtype=np.float64)
        return np.fromiter((self.func(x) for x in X), dtype=np.float64, count=X.shape[0])


class BudgetExhausted(Exception):
    """Raised by :class:`Context` once the evaluation or time budget is spent."""


class Context:
    """What an optimiser sees during a run: the problem, ``rng``, budgets and an evaluator."""

    def __init__(
        self,
        problem: Problem,
        rng: np.random.Generator,
        *,
        max_iter: int | None,
        max_evals: int | None,
        time_budget: float | None,
    ) -> None:
        self.problem = problem
        self.rng = rng
        self.max_iter = max_iter
        self.max_evals = max_evals
        self.time_budget = time_budget
        self.iteration = 0
        self.n_eval = 0
        self.best_x: NDArray[np.float64] | None = None
        self.best_f = math.inf
        self.t0 = time.perf_counter()

    @property
    def lower(self) -> NDArray[np.float64]:
        return self.problem.lower

    @property
    def upper(self) -> NDArray[np.float64]:
        return self.problem.upper

    @property
    def n_var(self) -> int:
        return self.problem.n_var

    @property
    def elapsed(self) -> float:
        return time.perf_counter() - self.t0

    @property
    def progress(self) -> float:
        """Fraction of the budget used, in ``[0, 1]``: the largest over the budgets given."""
        p = 0.0
        if self.max_iter:
            p = max(p, self.iteration / self.max_iter)
        if self.max_evals:
            p = max(p, self.n_eval / self.max_evals)
        if self.time_budget:
            p = max(p, self.elapsed / self.time_budget)
        return min(p, 1.0)

    @property
    def remaining_evals(self) -> int | None:
        return None if self.max_evals is None else max(self.max_evals - self.n_eval, 0)

    def exhausted(self) -> bool:
        if self.max_evals is not None and self.n_eval >= self.max_evals:
            return True
        if self.time_budget is not None and self.elapsed >= self.time_budget:
            return True
        return False

    def evaluate(self, X: ArrayLike) -> NDArray[np.float64]:
        """Evaluate ``X (n, n_var)`` within the budget; returns ``(n,)`` fitness.

        Rows past the evaluation budget are not evaluated and get ``inf``; NaN becomes ``inf``.
        Raises :class:`BudgetExhausted` when called with nothing left to spend.
        """
        X = np.atleast_2d(np.asarray(X, dtype=np.float64))
        if self.exhausted():
            raise BudgetExhausted
        n = X.shape[0]
        k = n if self.max_evals is None else min(n, self.max_evals - self.n_eval)
        F = np.full(n, np.inf)
        if k > 0:
            F[:k] = self.problem.evaluate(X[:k])
        F[np.isnan(F)] = np.inf
        self.n_eval += k
        if k > 0:
            i = int(np.argmin(F[:k]))
            # the first evaluation sets the best even when every value is inf (all NaN), so a
            # problem that is undefined everywhere gives an inf result rather than an error
            if F[i] < self.best_f or self.best_x is None:
                self.best_f = float(F[i])
                self.best_x = X[i].copy()
        return F


class Optimizer(ABC):
    """Base of every continuous metaheuristic: parameters in ``__init__``, state as arrays.

    Subclasses set ``name`` (the registry key) and implement :meth:`initialize` and
    :meth:`step`. They keep their population in attributes (``self.X``, ``self.F``, ...), draw
    random numbers only from ``ctx.rng``, and evaluate only through ``ctx.evaluate``.
    """

    name: ClassVar[str] = "optimizer"

    def __init__(self, pop_size: int = 30) -> None:
        if pop_size < 1:
            raise ValueError(f"pop_size must be >= 1, got {pop_size}")
        self.pop_size = int(pop_size)

    @abstractmethod
    def initialize(self, ctx: Context) -> None:
        """Create and evaluate the initial population."""

    @abstractmethod
    def step(self, ctx: Context) -> None:
        """Run one iteration of the algorithm's main loop."""

    def params(self) -> dict[str, Any]:
        """The settings of this optimiser, for reports and JSON.

        The arguments of ``__init__`` stored under the same attribute name, a settings
        dataclass (e.g. :class:`~weldplan.optim.algorithms.parapa.ParaPASettings`) by its
        fields in order; run state kept in attributes (``best_f``, counters) is not a setting
        and is left out.
        """
        names = [
            n
            for n, prm in inspect.signature(type(self).__init__).parameters.items()
            if n != "self" and prm.kind not in (prm.VAR_POSITIONAL, prm.VAR_KEYWORD)
        ]
        out = {}
        for n in names:
            v = getattr(self, n, None)
            if dataclasses.is_dataclass(v) and not isinstance(v, type):
                out.update(
                    (f.name, x) for f in dataclasses.fields(v) if _is_param(x := getattr(v, f.name))
                )
            elif hasattr(self, n) and _is_param(v):
                out[n] = v
        return out


def _is_param(v: Any) -> bool:
    return isinstance(v, (int, float, str, bool, type(None))) or (
        isinstance(v, (tuple, list)) and all(isinstance(x, (int, float, str, bool)) for x in v)
    )


@dataclass(frozen=True)
class OptimizeResult:
    """The outcome of :func:`minimize`.

    Attributes
    ----------
    x
        ``(n_var,) float``: best solution evaluated.
    f
        Its fitness.
    n_iter, n_eval
        Iterations completed and solutions evaluated.
    history
        ``(n_iter + 1,) float``: best fitness so far after initialisation and after each iteration.
    seconds
        Wall time of the run.
    algorithm, problem
        Registry name of the optimiser and name of the problem.
    seed
        The integer seed when one was given, else ``None``.
    params
        The optimiser's settings.
    message
        Why the run stopped.
    """

    x: tuple[float, ...]
    f: float
    n_iter: int
    n_eval: int
    history: tuple[float, ...]
    seconds: float
    algorithm: str
    problem: str
    seed: int | None = None
    params: dict[str, Any] = field(default_factory=dict)
    message: str = ""

    @property
    def x_array(self) -> NDArray[np.float64]:
        return np.asarray(self.x, dtype=np.float64)

    def to_json(self) -> str:
        return json.dumps(asdict(self), allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> OptimizeResult:
        d = json.loads(text)
        d["x"] = tuple(d["x"])
        d["history"] = tuple(d["history"])
        return cls(**d)


def minimize(
    problem: Problem,
    optimizer: Optimizer,
    *,
    max_iter: int | None = None,
    max_evals: int | None = None,
    time_budget: float | None = None,
    rng: RNGLike = None,
    callback: Callable[[Context], bool | None] | None = None,
) -> OptimizeResult:
    """Minimise ``problem`` with ``optimizer`` until a budget is spent.

    Parameters
    ----------
    max_iter, max_evals, time_budget
        Budgets in iterations, evaluations and seconds; at least one is required and the run stops
        at the first one reached. The evaluation budget is exact.
    rng
        Seed or Generator; the only source of randomness.
    callback
        ``callback(ctx)`` after every iteration; returning True stops the run.
    """
    if max_iter is None and max_evals is None and time_budget is None:
        raise ValueError("give at least one of max_iter, max_evals, time_budget")
    gen = as_generator(rng)
    ctx = Context(problem, gen, max_iter=max_iter, max_evals=max_evals, time_budget=time_budget)
    history: list[float] = []
    message = "max_iter reached"
    try:
        optimizer.initialize(ctx)
        history.append(ctx.best_f)
        while max_iter is None or ctx.iteration < max_iter:
            if ctx.exhausted():
                raise BudgetExhausted
            optimizer.step(ctx)
            ctx.iteration += 1
            history.append(ctx.best_f)
            if callback is not None and callback(ctx):
                message = "stopped by callback"
                break
    except BudgetExhausted:
        message = "evaluation or time budget spent"
        if len(history) < ctx.iteration + 1:
            history.append(ctx.best_f)
    if ctx.best_x is None:
        raise RuntimeError(f"{optimizer.name} evaluated no solution")
    return OptimizeResult(
        x=tuple(float(v) for v in ctx.best_x),
        f=float(ctx.best_f),
        n_iter=ctx.iteration,
        n_eval=ctx.n_eval,
        history=tuple(float(v) for v in history),
        seconds=ctx.elapsed,
        algorithm=optimizer.name,
        problem=problem.name,
        seed=seed_of(rng),
        params=optimizer.params(),
        message=message,
    )
