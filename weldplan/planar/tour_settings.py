"""How :func:`~weldplan.planar.tour_planner.plan_tour` plans a multi-goal tour: one frozen,
validated settings object (../shared/DESIGN.md: a stage takes its inputs and one settings object).

The pipelines it names (``default``, ``as-printed``, ``custom``) are those of
:mod:`weldplan.planar.tour_planner`. A contradictory choice (``as_printed`` with the any-angle
metric, ``taut=False`` with any-angle legs, an unknown metric) is a
:class:`~weldplan.errors.ConfigError` naming the field, raised once, when the settings are made.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from weldplan.errors import ConfigError
from weldplan.planar.tour_order import PAPER_ITER, PAPER_POP

#: the leg metrics: exact any-angle (Polyanya) or mesh-edge Dijkstra (paper 002)
METRICS = ("any-angle", "mesh")


@dataclass(frozen=True)
class TourSettings:
    """The ordering budget and the stages of a tour (:func:`~.tour_planner.plan_tour`).

    Attributes
    ----------
    metric
        ``"any-angle"`` (default: Polyanya's exact leg lengths and paths) or ``"mesh"``
        (paper 002's Dijkstra along mesh edges); ``None``: ``"any-angle"``, or ``"mesh"`` when
        ``taut=False`` (:meth:`resolved` gives the metric that runs).
    as_printed
        Paper 002 exactly: mesh metric, no polish, no funnel (overrides ``polish``, ``taut``).
    pop_size, max_iter, max_evals, time_budget
        Optimiser budget; paper 002 uses 500 and 500.
    two_opt
        2-opt decoding of every key (memetic; named deviation, see
        :mod:`weldplan.planar.multigoal`).
    polish
        Polish the optimiser's best order once with the sequencer's 2-opt + Or-opt iterated
        local search (default on; a named deviation). ``False`` gives the optimiser as printed.
    polish_kicks
        Kicks of that polish (default :data:`~weldplan.planar.tour_order.POLISH_KICKS_PER_STOP`
        per stop).
    taut
        With the mesh metric: pull each mesh-edge leg tight in its triangle corridor (funnel)
        before smoothing; ``False`` keeps the zig-zag (as paper 002). Any-angle legs are taut.
    smooth
        B-spline smoothing with the collision fallback (else the polyline is returned).
    """

    metric: str | None = None
    as_printed: bool = False
    pop_size: int = PAPER_POP
    max_iter: int = PAPER_ITER
    max_evals: int | None = None
    time_budget: float | None = None
    two_opt: bool = False
    polish: bool = True
    polish_kicks: int | None = None
    taut: bool = True
    smooth: bool = True

    def __post_init__(self) -> None:
        self.resolved()  # a contradiction fails here, once

    def resolved(self) -> tuple[str, bool, bool]:
        """``(metric, polish, taut)`` that run: ``as_printed`` forces paper 002's (mesh, no
        polish, no funnel); a ``metric`` of ``None`` follows ``taut``.

        Raises
        ------
        ConfigError
            For a contradictory choice, naming the field.
        """
        metric, polish, taut = self.metric, self.polish, self.taut
        if self.as_printed:
            if metric not in (None, "mesh"):
                raise ConfigError("as_printed uses paper 002's mesh metric", field="metric")
            return "mesh", False, False
        if metric is None:
            metric = "any-angle" if taut else "mesh"  # mesh-edge legs need the mesh's paths
        if metric not in METRICS:
            raise ConfigError(f"unknown metric {metric!r}; one of {METRICS}", field="metric")
        if metric == "any-angle" and not taut:
            raise ConfigError(
                "any-angle legs are taut; taut=False needs metric='mesh'", field="taut"
            )
        return metric, polish, taut

    @property
    def pipeline(self) -> str:
        """``"default"`` (any-angle costs, polish, B-spline), ``"as-printed"`` (paper 002: mesh
        costs, the optimiser's order, mesh-edge legs) or ``"custom"``."""
        metric, polish, taut = self.resolved()
        if self.as_printed or (metric == "mesh" and not polish and not taut):
            return "as-printed"
        return "default" if metric == "any-angle" and polish else "custom"

    @property
    def budget(self) -> dict[str, Any]:
        """The optimiser's budget as :func:`~weldplan.optim.core.minimize` and the result's
        ``params`` name it (``pop_size`` for the optimiser itself)."""
        return {"pop_size": self.pop_size, "max_iter": self.max_iter,
                "max_evals": self.max_evals, "time_budget": self.time_budget}  # fmt: skip


FIELDS = frozenset(f.name for f in dataclasses.fields(TourSettings))


def split_options(
    settings: TourSettings | None, options: dict[str, Any]
) -> tuple[TourSettings, dict[str, Any]]:
    """``(settings, optimiser parameters)``: the keywords that name a :class:`TourSettings`
    field laid over ``settings`` (default :class:`TourSettings`), the others left for the
    optimiser."""
    mine = {k: v for k, v in options.items() if k in FIELDS}
    base = TourSettings() if settings is None else settings
    st = dataclasses.replace(base, **mine) if mine else base
    return st, {k: v for k, v in options.items() if k not in FIELDS}
