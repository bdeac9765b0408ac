"""The registry of continuous optimisers by name, used by the CLI, the benchmarks and the tests.

Adding an algorithm: one file under ``weldplan/optim/algorithms/`` and one line here.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

from weldplan.errors import WeldplanError
from weldplan.optim.core import Optimizer

#: name -> "module:Class" (imported on first use so the CLI starts fast)
ALGORITHMS: dict[str, str] = {
    "random": "weldplan.optim.algorithms.random_search:RandomSearch",
    "sma": "weldplan.optim.algorithms.sma:SMA",
    "lrsma": "weldplan.optim.algorithms.lrsma:LRSMA",
    "isma": "weldplan.optim.algorithms.isma:ISMA",
    "pso": "weldplan.optim.algorithms.pso:PSO",
    "pso-w07": "weldplan.optim.algorithms.pso:PSOW07",
    "wpso": "weldplan.optim.algorithms.wpso:WPSO",
    "cpso": "weldplan.optim.algorithms.cpso:CPSO",
    "mpso": "weldplan.optim.algorithms.mpso:MPSO",
    "gwo": "weldplan.optim.algorithms.gwo:GWO",
    "woa": "weldplan.optim.algorithms.woa:WOA",
    "afsa": "weldplan.optim.algorithms.fish:AFSA",
    "hafsa": "weldplan.optim.algorithms.fish:HAFSA",
    "abc": "weldplan.optim.algorithms.bee:ABC",
    "mabc": "weldplan.optim.algorithms.bee:MABC",
    "parapa": "weldplan.optim.algorithms.parapa:ParaPA",
    "lso": "weldplan.optim.algorithms.lion:LSO",
    "ssa": "weldplan.optim.algorithms.sparrow:SSA",
    "aco": "weldplan.optim.algorithms.acor:ACOR",
}


def available() -> list[str]:
    """Registered algorithm names, sorted."""
    return sorted(ALGORITHMS)


def optimizer_class(name: str) -> type[Optimizer]:
    """The class registered as ``name`` (imported now)."""
    key = name.lower()
    if key not in ALGORITHMS:
        raise WeldplanError(f"unknown algorithm '{name}'; choose one of: {', '.join(available())}")
    module, cls = ALGORITHMS[key].split(":")
    return getattr(import_module(module), cls)


def get_optimizer(name: str, **params: Any) -> Optimizer:
    """A new optimiser of the registered ``name`` with ``params`` overriding its defaults."""
    return optimizer_class(name)(**params)
