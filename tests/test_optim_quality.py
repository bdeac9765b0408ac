"""Quality against exact answers (STYLE rule 17), parametrised over the registry.

- every algorithm reaches 1e-6 on the 10-d Sphere (optimum 0) within :data:`SPHERE_BUDGET`
  evaluations (002's protocol scale: population 30, 500 iterations), for three seeds;
- on the 10-d Rastrigin every algorithm beats random search at an equal evaluation budget;
- a starved budget does measurably worse (so the quality tests could fail). This one uses a
  *shifted* Sphere: several algorithms (SMA's ``vc * X``, pinhole opposition) contract towards
  the origin and solve the unshifted Sphere almost for free.

``random`` is the baseline and is excluded from the first test. An algorithm that needs a larger
budget to reach 1e-6 gets an entry in :data:`SPHERE_BUDGETS`, with the reason beside it.
"""

from __future__ import annotations

import numpy as np
import pytest

from weldplan.optim.core import minimize
from weldplan.optim.functions import get_function
from weldplan.optim.registry import available, get_optimizer

SEEDS = (0, 1, 2)
SPHERE_BUDGET = 15_000
#: per-algorithm overrides of SPHERE_BUDGET (name -> evaluations), each with its reason
SPHERE_BUDGETS: dict[str, int] = {
    # 003's population: 3 colonies of NP = 50, 150 bees an iteration (100 iterations at 15k)
    "mabc": 30_000,
    # 3 swarms of 003's NP = 50: 150 particles an iteration, and w falls 0.9 -> 0.1 over the
    # budget, so the swarm settles late (1e-6 after about 400 iterations)
    "parapa": 60_000,
}
#: (test, algorithm) -> why it is a known, measured shortfall; run as strict xfail so a fix
#: shows up as XPASS
SHORTFALLS: dict[tuple[str, str], str] = {
    ("sphere", "afsa"): "fixed visual/step (001: half the box side): ~7e3 on 10-d Sphere",
    ("sphere", "hafsa"): "prey probes and detection radius have fixed scale: ~1 on 10-d Sphere",
    ("rastrigin", "afsa"): "non-greedy moves of fixed size: no better than random search in 10-d",
    ("starved", "afsa"): "its 10-d best improves < 3x from 300 to 15k evaluations",
}


def _params(test: str) -> list:  # type: ignore[type-arg]
    return [
        pytest.param(a, marks=pytest.mark.xfail(strict=True, reason=SHORTFALLS[test, a]))
        if (test, a) in SHORTFALLS
        else a
        for a in ALGOS
    ]


RASTRIGIN_BUDGET = 6_000
STARVED, FED = 300, 15_000
BASELINE = "random"

ALGOS = [a for a in available() if a != BASELINE]


@pytest.mark.parametrize("name", _params("sphere"))
def test_sphere_10d_below_1e_6(name: str) -> None:
    p = get_function("sphere", 10)
    budget = SPHERE_BUDGETS.get(name, SPHERE_BUDGET)
    for seed in SEEDS:
        r = minimize(p, get_optimizer(name), max_evals=budget, rng=seed)
        assert r.f < 1e-6, f"{name} seed {seed}: {r.f:.3g} after {r.n_eval} evaluations"


def _median_f(name: str, problem, budget: int) -> float:  # type: ignore[no-untyped-def]
    return float(
        np.median(
            [minimize(problem, get_optimizer(name), max_evals=budget, rng=s).f for s in SEEDS]
        )
    )


@pytest.fixture(scope="module")
def random_rastrigin() -> list[float]:
    p = get_function("rastrigin", 10)
    return [
        minimize(p, get_optimizer(BASELINE), max_evals=RASTRIGIN_BUDGET, rng=s).f for s in SEEDS
    ]


@pytest.mark.parametrize("name", _params("rastrigin"))
def test_rastrigin_beats_random_search(name: str, random_rastrigin: list[float]) -> None:
    p = get_function("rastrigin", 10)
    worst = max(
        minimize(p, get_optimizer(name), max_evals=RASTRIGIN_BUDGET, rng=s).f for s in SEEDS
    )
    assert worst < min(random_rastrigin), (
        f"{name}: {worst:.3g} vs random {min(random_rastrigin):.3g}"
    )


@pytest.mark.parametrize("name", _params("starved"))
def test_starved_budget_does_worse(name: str) -> None:
    p = get_function("sphere", 10, shift=np.linspace(-60.0, 70.0, 10))
    starved = _median_f(name, p, STARVED)
    fed = _median_f(name, p, FED)
    assert starved > 3.0 * fed + 1e-9, f"{name}: starved {starved:.3g} vs fed {fed:.3g}"
