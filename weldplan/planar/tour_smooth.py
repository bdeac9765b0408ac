"""B-spline smoothing of a tour polyline (paper 002 eq. 14) with the collision check and the
fallback to the polyline; the grazing-tolerant segment check that judges tour paths.

Moved out of :mod:`weldplan.planar.multigoal` (which re-exports these names) to keep that module
to scenarios, distances and the order encoding.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

log = logging.getLogger(__name__)

#: B-spline degree (cubic) and samples per control point when smoothing
SPLINE_DEGREE = 3
SAMPLES_PER_CONTROL = 8
#: rounds of pulling the B-spline onto the polyline where it collides
SMOOTH_ROUNDS = 50


def segments_clear(world: Any, A: ArrayLike, B: ArrayLike, depth_tol: float | None = None) -> Any:
    """Collision check of path segments ``A -> B (s, 2)`` that tolerates grazing noise.

    A segment passes when ``world.segments_free`` says so, or when none of five points along it
    is deeper than ``depth_tol`` inside an obstacle (default ``GRAZE_TOL`` x map scale, the
    planar core's grazing tolerance; on a navigation mesh: when the five points are in the mesh,
    its boundary included): a B-spline that runs along an obstacle side, as mesh paths
    do, sits on it up to rounding (1e-14 inside), which an exact check would call a collision.
    """
    from weldplan.geometry.obstacles2d import GRAZE_TOL

    A = np.asarray(A, dtype=np.float64)
    B = np.asarray(B, dtype=np.float64)
    ok = np.asarray(world.segments_free(A, B), dtype=bool)
    if ok.all():
        return ok
    a, b = A[~ok], B[~ok]
    t = np.linspace(0.0, 1.0, 5)[:, None, None]
    Q = a + t * (b - a)
    if hasattr(world, "clearance"):
        tol = GRAZE_TOL * float(world.scale) if depth_tol is None else float(depth_tol)
        ok[~ok] = np.max(-np.asarray(world.clearance(Q)), axis=0) <= tol
    elif hasattr(world, "contains_free"):  # a navigation mesh: boundary points count as free
        ok[~ok] = np.all(world.contains_free(Q), axis=0)
    return ok


def _clamped_bspline(
    ctrl: NDArray[np.float64], mult: NDArray[np.int64], n: int, degree: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Clamped uniform B-spline of ``ctrl (k, 2)`` (as :func:`bspline_path`) sampled at ``n``
    uniform parameters plus the knots where it passes through a control point repeated
    ``degree`` times (so the sampled polyline keeps those corners exactly).

    Returns the points ``(q, 2)`` and their parameters ``(q,)``.
    """
    from scipy.interpolate import BSpline

    k = len(ctrl)
    p = min(int(degree), k - 1)
    inner = np.linspace(0.0, 1.0, k - p + 1)
    knots = np.concatenate([np.zeros(p), inner, np.ones(p)])
    starts = np.cumsum(mult) - mult  # first copy of each polyline vertex in ctrl
    through = inner[np.clip(starts[mult >= p], 0, k - p)]
    u = np.unique(np.concatenate([np.linspace(0.0, 1.0, int(n)), through]))
    pts = BSpline(knots, ctrl, p, axis=0)(u)
    pts[0], pts[-1] = ctrl[0], ctrl[-1]
    return pts, u


def smooth_tour(
    points: ArrayLike,
    stops_at: ArrayLike,
    world: Any,
    *,
    degree: int = SPLINE_DEGREE,
    samples_per_control: int = SAMPLES_PER_CONTROL,
    rounds: int = SMOOTH_ROUNDS,
) -> tuple[NDArray[np.float64], bool]:
    """B-spline smoothing of a tour polyline (002 eq. 14) with a collision check and fallback.

    Parameters
    ----------
    points
        ``(p, 2)``: the polyline (its vertices become the control points).
    stops_at
        Indices into ``points`` of the stops; they get multiplicity ``degree`` so the curve
        passes through them.
    world
        Anything with ``segments_free(A, B)`` (an :class:`Obstacles2D` with the map frame);
        judged by :func:`segments_clear`.

    Returns
    -------
    curve
        ``(q, 2)``: the smoothed path, or ``points`` when no collision-free smoothing was found.
    smoothed
        Whether ``curve`` is the B-spline.
    """
    P = np.asarray(points, dtype=np.float64)
    mult = np.ones(len(P), dtype=np.int64)
    mult[np.asarray(stops_at, dtype=np.int64)] = degree
    rounds_used = 0
    while rounds_used <= rounds:
        ctrl = np.repeat(P, mult, axis=0)
        owner = np.repeat(np.arange(len(P)), mult)
        n = max(2, samples_per_control * len(ctrl))
        curve, u = _clamped_bspline(ctrl, mult, n, degree)
        bad = ~segments_clear(world, curve[:-1], curve[1:])
        if not bad.any():
            return curve, True
        # parameter of a bad sample -> nearest control point(s) of the clamped uniform spline
        ub = 0.5 * (u[:-1] + u[1:])[bad]
        k = len(ctrl) - 1
        centre = np.clip(np.round(ub * k).astype(np.int64), 0, k)
        hit = np.unique(
            np.concatenate([owner[np.clip(centre + s, 0, k)] for s in range(-degree, degree + 1)])
        )
        if np.all(mult[hit] >= degree):
            break
        mult[hit] = degree
        rounds_used += 1
    log.info("B-spline smoothing collides after %d rounds; keeping the polyline", rounds)
    return P, False
