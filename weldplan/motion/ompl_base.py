"""The OMPL plumbing that weldplan's sampling planners share: importing OMPL, checking arguments,
seeding OMPL's RNG and calling a Python motion check from OMPL.

:mod:`weldplan.motion.sampling` (one path per call: :func:`~weldplan.motion.sampling.plan_rn`,
:func:`~weldplan.motion.sampling.plan_se3`) and :mod:`weldplan.motion.roadmap` (a reusable
roadmap) both build OMPL problems on these; the public names here are re-exported by
:mod:`weldplan.motion.sampling`, where callers import them. Conventions (states as numpy arrays,
the process-wide seed) are the sampling module's notes.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, PlanningError

#: largest deviation of a quaternion's norm from 1 that is accepted (and then normalised away)
QUAT_NORM_TOL = 1e-6
#: OMPL seeds must be positive 32-bit integers (0 is ignored by OMPL)
_SEED_MOD = 2**32 - 1

StateCheck = Callable[[NDArray[np.float64]], bool]
MotionCheck = Callable[[NDArray[np.float64], NDArray[np.float64]], bool]


class SamplingArgumentError(PlanningError, ValueError):
    """A bad argument to :func:`~weldplan.motion.sampling.plan_rn` /
    :func:`~weldplan.motion.sampling.plan_se3` or a :class:`~weldplan.motion.roadmap.Roadmap`
    (shapes, bounds, planner name, time).

    A :class:`~weldplan.errors.PlanningError` (the agreed interface of the OMPL wrapper) and a
    ``ValueError`` (the project's rule for input errors of the public API).
    """


def ompl_available() -> bool:
    """True when OMPL's Python bindings can be imported."""
    try:
        _import_ompl()
    except ConfigError:
        return False
    return True


def _import_ompl() -> tuple[Any, Any, Any]:
    try:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise ConfigError(
            f"OMPL is not installed ({exc}); install the extra: pip install 'weldplan[ompl]'",
            field="planner",
        ) from exc
    return ob, og, ou


# --------------------------------------------------------------------------- argument checks


def _vector(name: str, value: ArrayLike, d: int | None = None) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim != 1 or (d is not None and arr.shape[0] != d) or arr.shape[0] == 0:
        want = f"({d},)" if d is not None else "(d,) with d >= 1"
        raise SamplingArgumentError(f"{name} must have shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise SamplingArgumentError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def _check_box(lower: NDArray, upper: NDArray, points: dict[str, NDArray]) -> None:
    if np.any(upper <= lower):
        raise SamplingArgumentError(
            f"upper must exceed lower on every axis: lower {lower.tolist()}, upper {upper.tolist()}"
        )
    for name, p in points.items():
        if np.any(p < lower) or np.any(p > upper):
            raise SamplingArgumentError(
                f"{name} {p.tolist()} lies outside the bounds [{lower.tolist()}, {upper.tolist()}]"
            )


def _unit_quat(name: str, value: ArrayLike) -> NDArray[np.float64]:
    q = _vector(name, value, 4)
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > QUAT_NORM_TOL:
        raise SamplingArgumentError(
            f"{name} must be a unit quaternion (w, x, y, z), got norm {norm:.9g}"
        )
    return q / norm


def _ompl_seed(seed: int | np.random.Generator | None) -> int | None:
    """OMPL seed (positive 32-bit) for ``seed``; a Generator contributes one draw."""
    if seed is None:
        return None
    if isinstance(seed, np.random.Generator):
        seed = int(seed.integers(0, _SEED_MOD))
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool):
        raise SamplingArgumentError(f"seed must be an int, a numpy Generator or None, got {seed!r}")
    return int(seed) % _SEED_MOD + 1


# --------------------------------------------------------------------------- motion checks


@functools.cache
def _validator_class() -> type:
    """An OMPL ``MotionValidator`` subclass calling a Python ``check(a, b)`` on numpy states
    (built once: OMPL is imported lazily)."""
    ob = _import_ompl()[0]

    class _Validator(ob.MotionValidator):  # type: ignore[misc, name-defined]
        def __init__(self, si: Any, read: Callable, check: MotionCheck) -> None:
            super().__init__(si)
            self._read = read
            self._check = check

        def checkMotion(self, s1: Any, s2: Any) -> bool:  # OMPL's virtual method
            return bool(self._check(self._read(s1), self._read(s2)))

    return _Validator


def _motion_validator(si: Any, read: Callable, check: MotionCheck) -> Any:
    """An OMPL MotionValidator for ``si`` that calls the Python ``check(a, b)``."""
    return _validator_class()(si, read, check)
