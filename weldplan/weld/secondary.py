"""The secondary optimisation (SO) of Wang et al. 2017, section 4.3: shortcuts between the points
of a grid route, checked segment by segment (split out of :mod:`weldplan.weld.local`)."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.pathcore import polyline_length as _length
from weldplan.geometry.pathcore import split_segments

log = logging.getLogger(__name__)

__all__ = ["SO_LENGTH_TOL", "SecondaryResult", "polyline_length", "secondary_optimization"]


def polyline_length(points: ArrayLike) -> float:
    """Length (mm) of the polyline ``points (n, 3)``: the path core's
    :func:`weldplan.geometry.pathcore.polyline_length` on points read as ``(n, 3)``."""
    return _length(np.asarray(points, dtype=np.float64).reshape(-1, 3))


#: two route lengths closer than this (mm) are "the same" in step 8 of section 4.3
SO_LENGTH_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class SecondaryResult:
    """Outcome of :func:`secondary_optimization`.

    Attributes
    ----------
    points
        ``(n, 3) float`` the optimised route (mm), same first and last point as the input.
    passes
        Passes of steps 1-8 run.
    checks
        Segment checks made.
    converged
        False when ``max_passes`` or the deadline stopped it before the length settled.
    bad_segment
        With ``check_adjacent``: index ``k`` of the first segment ``k -> k + 1`` of the input
        that had to be kept and failed the check (``points`` is then the input); ``-1`` when a
        kept segment failed in a later pass (it cannot happen in exact arithmetic: later
        segments are pieces of checked ones); ``None`` when every kept segment is free.
    """

    points: NDArray[np.float64]
    passes: int
    checks: int
    converged: bool
    bad_segment: int | None = None


def secondary_optimization(
    points: ArrayLike,
    segment_free: Callable[[NDArray[np.float64], NDArray[np.float64]], bool],
    *,
    step: float = 5.0,
    max_passes: int = 100,
    deadline: float | None = None,
    check_adjacent: bool = False,
) -> SecondaryResult:
    """The secondary optimisation (SO) of Wang et al. 2017, section 4.3, steps 1-10.

    From the last kept point ``p``, try the points of the route from the last one backwards and
    keep the first ``q`` that ``p`` sees in a straight line (steps 3-6; the point right after
    ``p`` is kept without a check, as in step 4: consecutive points of the input must be
    connected by free segments). Repeat from ``q`` until the end (step 7). If the new route is
    shorter (step 8), split its segments longer than ``step`` into points, reverse it and start
    again (step 9); otherwise it is the result (step 10).

    Parameters
    ----------
    points
        ``(n, 3) float`` route (mm) whose consecutive points are joined by free segments.
    segment_free
        ``segment_free(a, b) -> bool`` for points ``(3,)``: the straight-line check (the FCL
        capsule at the clearance in weldplan).
    step
        The split length of step 9 (5 mm, the grid step, in the paper).
    max_passes
        Stop after this many passes (a guard; the length decreases at every pass).
    deadline
        ``time.perf_counter()`` value after which it stops and returns the route so far (still
        collision-free: every pass only replaces points by checked shortcuts).
    check_adjacent
        Also check the segment to the next point when step 4 keeps it without a check, and stop
        with ``bad_segment`` when it fails (weldplan's grid routes are only candidates: a
        lattice move can graze a sharp edge; the paper assumes they are free).

    Returns
    -------
    SecondaryResult
        The route, oriented like the input, never longer than the input.
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    first = P[0].copy()
    rout = P
    checks = 0
    passes = 0
    converged = False
    result = P
    while passes < max_passes:
        if passes and deadline is not None and time.perf_counter() > deadline:
            break  # the first pass always runs: it is the one that checks the input's moves
        passes += 1
        n = len(rout)
        keep = [0]
        i = 0
        while i < n - 1:
            q = n - 1
            while q > i + 1:
                checks += 1
                if segment_free(rout[i], rout[q]):
                    break
                q -= 1
            if check_adjacent and q == i + 1:
                checks += 1
                if not segment_free(rout[i], rout[q]):
                    bad = i if passes == 1 else -1
                    return SecondaryResult(P, passes, checks, False, bad)
            keep.append(q)
            i = q
        routi = rout[keep]
        result = routi
        if polyline_length(rout) - polyline_length(routi) <= SO_LENGTH_TOL:
            converged = True
            break
        rout = split_segments(routi, step)[::-1]
    if not np.array_equal(result[0], first):
        result = result[::-1]
    return SecondaryResult(np.ascontiguousarray(result), passes, checks, converged)
