"""How an OMPL run searches: one frozen, validated settings object for
:func:`~weldplan.motion.sampling.plan_rn` and :func:`~weldplan.motion.sampling.plan_se3`.

A planner call takes its problem (start, goal, box, the caller's checks), its per-call seed and
stop, and one :class:`SamplingSettings` (../shared/DESIGN.md: "a stage takes its inputs and one
frozen, validated settings object"; the tool and robot stages' settings follow the same shape,
weldplan/tool/settings.py and weldplan/robot/settings.py). The settings are checked once, when
they are made, and a bad field is a
:class:`~weldplan.motion.ompl_base.SamplingArgumentError` naming it (a
:class:`~weldplan.errors.PlanningError` and a ``ValueError``, the wrapper's agreed error).

The planner functions keep their keyword conveniences (``planner=``, ``time_s=``...): each is a
field of :class:`SamplingSettings` laid over the ``settings`` given
(:func:`resolve_options`), so ``plan_rn(..., planner="rrtconnect", time_s=2)`` and
``plan_rn(..., settings=SamplingSettings(planner="rrtconnect", time_s=2))`` are one call.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypedDict

import numpy as np

from weldplan.motion.ompl_base import SamplingArgumentError
from weldplan.options import laid_over

#: weldplan's planner names -> OMPL ``ompl.geometric`` classes. Every planner here was checked to
#: work with a Python motion validator (OMPL's two-state ``checkMotion``).
PLANNERS: dict[str, str] = {
    "bitstar": "BITstar",
    "rrtstar": "RRTstar",
    "informedrrtstar": "InformedRRTstar",
    "rrtconnect": "RRTConnect",
    "prmstar": "PRMstar",
}

#: OMPL's default state-validity checking resolution (fraction of the space's maximum extent)
DEFAULT_RESOLUTION = 0.01
#: default planner: BIT* (Gammell, Srinivasa and Barfoot, ICRA 2015), anytime and asymptotically
#: optimal
DEFAULT_PLANNER = "bitstar"
#: default wall-clock limit of one run, s (a safety net where ``max_checks`` budgets the work)
DEFAULT_TIME_S = 1.0
#: default SE(3) metric weight, mm per rad of rotation
DEFAULT_ROT_WEIGHT = 100.0


@dataclass(frozen=True)
class SamplingSettings:
    """How one OMPL run searches (module notes of :mod:`weldplan.motion.sampling`).

    Attributes
    ----------
    planner
        A name in :data:`PLANNERS`.
    time_s
        Wall-clock limit, s: with ``max_checks`` a safety net (a run it ends is reported
        ``ended="clock"``, not reproducible); without, anytime planners use all of it and
        ``rrtconnect`` stops at its first solution.
    resolution
        Fraction of the space's extent between the states OMPL checks on a motion when the
        caller gives no motion check, in (0, 1] (OMPL's default 0.01).
    simplify
        Run OMPL's path simplifier to convergence (``simplifyMax``) after planning.
    max_checks
        Work budget: planning ends once the caller's state and motion checks together have been
        called this often (the same count on any machine); ``None``: no budget.
    reach
        The planner's ``range`` where it has one (the longest motion one step adds, in the
        space's metric: mm, or mm + ``rot_weight`` x rad in SE(3)); ``None``: OMPL's default (a
        fifth of the space's extent).
    rot_weight
        SE(3) only: mm per rad, the metric is position distance + ``rot_weight`` x rotation
        angle.
    """

    planner: str = DEFAULT_PLANNER
    time_s: float = DEFAULT_TIME_S
    resolution: float = DEFAULT_RESOLUTION
    simplify: bool = True
    max_checks: int | None = None
    reach: float | None = None
    rot_weight: float = DEFAULT_ROT_WEIGHT

    def __post_init__(self) -> None:
        if self.planner not in PLANNERS:
            raise SamplingArgumentError(
                f"planner: unknown planner {self.planner!r}; choose one of {', '.join(PLANNERS)}"
            )
        if not (_real(self.time_s) and self.time_s > 0):
            raise SamplingArgumentError(
                f"time_s must be a positive number of seconds, got {self.time_s}"
            )
        if not (_real(self.resolution) and 0.0 < self.resolution <= 1.0):
            raise SamplingArgumentError(
                f"resolution is a fraction of the space's extent in (0, 1], got {self.resolution}"
            )
        m = self.max_checks
        if m is not None and (isinstance(m, bool) or int(m) < 1):
            raise SamplingArgumentError(f"max_checks must be a positive count, got {m!r}")
        if self.reach is not None and not (_real(self.reach) and self.reach > 0):
            raise SamplingArgumentError(f"reach must be a positive length, got {self.reach!r}")
        if not (_real(self.rot_weight) and self.rot_weight > 0):
            raise SamplingArgumentError(
                f"rot_weight must be a positive mm per rad, got {self.rot_weight}"
            )


def _real(v: Any) -> bool:
    """``v`` is a finite real number (not a bool)."""
    return (
        isinstance(v, (int, float, np.integer, np.floating))
        and not isinstance(v, bool)
        and math.isfinite(v)
    )


class SamplingOptions(TypedDict, total=False):
    """The keyword conveniences of the planner functions: the per-call ``seed`` and ``stop``, and
    any field of :class:`SamplingSettings` (laid over the ``settings`` given)."""

    seed: int | np.random.Generator | None
    stop: Callable[[], bool] | None
    planner: str
    time_s: float
    resolution: float
    simplify: bool
    max_checks: int | None
    reach: float | None
    rot_weight: float


def resolve_options(
    caller: str, settings: SamplingSettings | None, options: dict[str, Any]
) -> tuple[SamplingSettings, int | np.random.Generator | None, Callable[[], bool] | None]:
    """``(settings, seed, stop)`` of a planner call: ``options``' settings fields laid over
    ``settings`` (default :class:`SamplingSettings`, :func:`weldplan.options.laid_over`),
    validated once; an unknown keyword is a ``TypeError`` naming ``caller``, as Python's own."""
    seed, stop = options.pop("seed", None), options.pop("stop", None)
    return laid_over(SamplingSettings, settings, options, caller), seed, stop
