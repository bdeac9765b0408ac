"""Checks of the public planning API's arguments, before any work.

:class:`~weldplan.weld.pipeline.PlanConfig` and :func:`~weldplan.weld.pipeline.plan_route` call
these so that a wrong type, a NaN or an out-of-range value ends in one
:class:`~weldplan.errors.ConfigError` (a ``ValueError``) naming the setting, instead of a
``TypeError`` from deep inside numpy or the sequencer minutes later. The CLI goes through the same
checks, so the messages are the same there (``--seed -1`` reads ``seed must be ...``).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from typing import Any

import numpy as np

from weldplan.errors import ConfigError

#: local planners for blocked pairs (:class:`~weldplan.weld.pipeline.PlanConfig` ``planner``);
#: ``ompl`` (OMPL's BIT* on weldplan's FCL checks, :mod:`weldplan.weld.local_ompl`) needs the extra
PLANNERS = ("so-aco", "aco", "exact", "ompl")
#: sequencers (``PlanConfig.sequencer``): auto = Held-Karp up to 13 joints, else nn + polish
SEQUENCERS = ("auto", "fast-tsp", "pso", "exact", "nn")


def _is_real(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, (bool, np.bool_))


def _is_int(v: Any) -> bool:
    return isinstance(v, numbers.Integral) and not isinstance(v, (bool, np.bool_))


def positive_mm(name: str, v: Any) -> float:
    """``v`` as a finite number > 0 (mm), else a ConfigError naming ``name``."""
    if not (_is_real(v) and math.isfinite(v) and v > 0):
        raise ConfigError(f"{name} must be a positive number of mm, got {v!r}", field=name)
    return float(v)


def optional_positive(name: str, v: Any, unit: str, *, allow_inf: bool = False) -> float | None:
    """None, or a number > 0 (finite unless ``allow_inf``)."""
    if v is None:
        return None
    ok = _is_real(v) and not math.isnan(v) and v > 0 and (allow_inf or math.isfinite(v))
    if not ok:
        raise ConfigError(
            f"{name} must be a positive number of {unit} or None, got {v!r}", field=name
        )
    return float(v)


def integer(name: str, v: Any, minimum: int, *, optional: bool = False) -> int | None:
    """An integer ``>= minimum`` (None allowed when ``optional``)."""
    if v is None and optional:
        return None
    if not (_is_int(v) and v >= minimum):
        what = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
        raise ConfigError(f"{name} must be {what}, got {v!r}", field=name)
    return int(v)


def flag(name: str, v: Any) -> bool:
    if not isinstance(v, (bool, np.bool_)):
        raise ConfigError(f"{name} must be True or False, got {v!r}", field=name)
    return bool(v)


def choice(name: str, v: Any, choices: tuple[str, ...]) -> str:
    if not (isinstance(v, str) and v in choices):
        raise ConfigError(f"unknown {name} {v!r}; choose one of {choices}", field=name)
    return v


def seed(v: Any) -> Any:
    """The ``rng`` of a stochastic entry point: None, an integer >= 0 (any size, as numpy takes),
    a ``SeedSequence`` or a ``Generator``."""
    if v is None or isinstance(v, (np.random.Generator, np.random.SeedSequence)):
        return v
    if _is_int(v) and v >= 0:
        return int(v)
    raise ConfigError(
        f"seed (rng) must be an integer >= 0 (or a numpy Generator / SeedSequence), got {v!r}",
        field="seed",
    )


def check_config(c: Any) -> None:
    """Every field of a :class:`~weldplan.weld.pipeline.PlanConfig` (normalised in place)."""
    put = object.__setattr__
    choice("planner", c.planner, PLANNERS)
    if c.planner == "ompl":
        from weldplan.motion.sampling import ompl_available

        if not ompl_available():
            raise ConfigError(
                "planner 'ompl' needs OMPL's Python bindings: pip install 'weldplan[ompl]'",
                field="planner",
            )
    choice("sequencer", c.sequencer, SEQUENCERS)
    choice("pairs", c.pairs, ("lazy", "all"))
    put(c, "clearance", positive_mm("clearance", c.clearance))
    put(c, "pitch", positive_mm("pitch", c.pitch))
    put(c, "smooth_spacing", positive_mm("smooth_spacing", c.smooth_spacing))
    if not (_is_real(c.margin) and math.isfinite(c.margin) and c.margin >= 0):
        raise ConfigError(f"margin must be >= 0 mm, got {c.margin!r}", field="margin")
    put(c, "margin", float(c.margin))
    put(c, "candidates", integer("candidates", c.candidates, 1, optional=True))
    if c.candidates is not None and c.pairs == "all":
        raise ConfigError(
            "candidates needs pairs='lazy' (pairs='all' plans every pair)", field="candidates"
        )
    put(
        c,
        "candidate_radius",
        optional_positive("candidate_radius", c.candidate_radius, "mm", allow_inf=True),
    )
    for name in ("polish", "warm_rounds", "known_first", "skip_unreachable", "refine", "smooth"):
        put(c, name, flag(name, getattr(c, name)))
    for name in ("local_time_budget", "sequence_time_budget"):
        put(c, name, optional_positive(name, getattr(c, name), "seconds"))
    put(c, "memory_limit", optional_positive("memory_limit", c.memory_limit, "GB"))
    put(c, "gap_target", optional_positive("gap_target", c.gap_target, "(relative gap)"))
    put(c, "gap_rounds", integer("gap_rounds", c.gap_rounds, 1))
    put(c, "max_rounds", integer("max_rounds", c.max_rounds, 1))
    put(c, "warm_kicks", integer("warm_kicks", c.warm_kicks, 0, optional=True))
    put(c, "demand_neighbours", integer("demand_neighbours", c.demand_neighbours, 0))
    aco = _aco(c.aco)
    aco.setdefault("refine", c.refine)  # the local planner reads it from its params
    put(c, "aco", aco)
    put(c, "pso", _pso(c.pso))


def _mapping(name: str, v: Any) -> dict[str, Any]:
    if not isinstance(v, Mapping) or not all(isinstance(k, str) for k in v):
        raise ConfigError(
            f"{name} must be a mapping of parameter names to values, got {v!r}", field=name
        )
    return dict(v)


def _aco(v: Any) -> dict[str, Any]:
    aco = _mapping("aco", v)
    for key in ("n_iterations", "n_ants"):
        if key in aco:
            integer(f"aco[{key!r}]", aco[key], 1)
    return aco


def _pso(v: Any) -> dict[str, Any]:
    from dataclasses import fields

    from weldplan.optim.discrete.tsp_pso import PSOParams

    pso = _mapping("pso", v)
    names = {f.name for f in fields(PSOParams)}
    unknown = sorted(set(pso) - names)
    if unknown:
        raise ConfigError(
            f"pso: unknown parameter(s) {unknown}; known: {sorted(names)}", field="pso"
        )
    for key in ("iterations", "particles"):
        if key in pso:
            integer(f"pso[{key!r}]", pso[key], 0 if key == "iterations" else 1)
    for key in ("c1", "c2", "weight"):
        if key in pso and not (_is_real(pso[key]) and math.isfinite(pso[key]) and pso[key] >= 0):
            raise ConfigError(f"pso[{key!r}] must be a number >= 0, got {pso[key]!r}", field="pso")
    return pso


def check_plan_arguments(cell: Any, rng: Any, executor: Any, progress: Any) -> None:
    """The arguments of :func:`~weldplan.weld.pipeline.plan_route` but its config (which
    :class:`~weldplan.weld.pipeline.PlanConfig` checks), before any work."""
    missing = [
        a for a in ("joints", "virtual_xyz", "collision", "clearance") if not hasattr(cell, a)
    ]
    if missing:
        raise ConfigError(
            f"cell must be a Cell (weldplan.load_cell or build_cell), got {type(cell).__name__} "
            f"without {', '.join(missing)}",
            field="cell",
        )
    seed(rng)
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise ConfigError(
            "executor must be a concurrent.futures.Executor or None, "
            f"got {type(executor).__name__}",
            field="executor",
        )
    if progress is not None and not callable(progress):
        raise ConfigError(
            f"progress must be a callable progress(stage, done, total) or None, got {progress!r}",
            field="progress",
        )
