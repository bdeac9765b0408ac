"""Smooth paths a robot can follow: a C2 cubic B-spline through a refined polyline, checked for
clearance on a sampling that is conservative by construction (issue 15 item 2).

The curve is :func:`weldplan.geometry.splines.interpolating_bspline` through the polyline's
vertices (centripetal parameter, natural ends): it passes through every vertex, and around a bend
that wraps an obstacle it runs outside the polyline's corner, away from the obstacle.

The check (why it cannot miss a collision between samples)
----------------------------------------------------------
Between two parameters ``u0 < u1`` of one knot span, with ``h = u1 - u0``, a curve deviates from
its chord ``s(u0) -> s(u1)`` by at most ``h^2 / 8 * max |s''|`` (the remainder of linear
interpolation, which holds for vector-valued curves: the error is a positive-weighted average of
``s''`` whose weights integrate to at most ``h^2 / 8``). On a knot span of a cubic spline ``s''``
is linear, so ``max |s''|`` over ``[u0, u1]`` is the larger of ``|s''(u0)|`` and ``|s''(u1)|`` (a
norm of a linear function is convex): the bound ``e`` is computed exactly, not estimated. The
ball of radius ``clearance`` swept along the curve piece therefore lies inside the capsule of
radius ``clearance + e`` around the chord, and that capsule is what the obstacle's
``segments_free`` checks (python-fcl in 3D). Spans are split until ``e <= max_deviation``, so the
check asks at most that much more than the clearance.

Metrics (per path, so per leg of a route): length (chords of the dense sampling, within
``max_deviation``-sized pieces), maximum curvature ``|s' x s''| / |s'|^3`` (in R^d,
``sqrt(|s'|^2 |s''|^2 - (s'.s'')^2) / |s'|^3``) on the same sampling, and the minimum clearance
measured at the samples (``distance``), beside the clearance the check proves.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import BSpline

from weldplan.geometry.pathcore import PathObstacle, as_path, polyline_length
from weldplan.geometry.splines import interpolating_bspline

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

__all__ = ["MAX_DEVIATION", "SmoothPath", "curvature", "smooth_path"]

#: largest deviation (mm) of the curve from a checked chord: the slack the check adds
MAX_DEVIATION = 0.05
#: guard on the number of checked pieces of one curve
MAX_PIECES = 200_000


def curvature(d1: FloatArray, d2: FloatArray) -> FloatArray:
    """Curvature (1/mm) from first and second derivatives ``(m, d)`` in any dimension."""
    a = np.einsum("ij,ij->i", d1, d1)
    b = np.einsum("ij,ij->i", d2, d2)
    c = np.einsum("ij,ij->i", d1, d2)
    num = np.sqrt(np.maximum(a * b - c * c, 0.0))
    return np.divide(num, a**1.5, out=np.zeros_like(num), where=a > 0)


@dataclass(frozen=True, eq=False)
class SmoothPath:
    """A checked C2 curve (module docstring).

    Attributes
    ----------
    knots, control, degree
        The B-spline: knots ``(m,)`` on ``[0, 1]``, control points ``(k, d)`` (mm) and degree
        (3; 1 for a path of two points).
    params
        ``(p,)`` the parameters of the checked samples (every knot among them).
    length
        Length (mm) of the sampled curve.
    max_curvature
        Largest curvature (1/mm) at the samples; ``1 / max_curvature`` is the tightest radius.
    min_clearance
        Smallest distance (mm) from a sample to the obstacle.
    max_deviation
        Largest bound ``e`` (mm) of a piece: every piece was checked at ``clearance + e``.
    free
        Every piece passed; False: the curve leaves the clearance somewhere (do not use it).
    status
        One line.
    """

    knots: FloatArray
    control: FloatArray
    degree: int
    params: FloatArray
    length: float
    max_curvature: float
    min_clearance: float
    max_deviation: float
    free: bool
    status: str

    @property
    def spline(self) -> BSpline:
        return BSpline(self.knots, self.control, self.degree)

    def waypoints(self, step: float | None = None) -> FloatArray:
        """Dense waypoints ``(n, d)`` on the curve: the checked samples, or points every
        ``step`` mm of parameter-proportional spacing when given (for an export)."""
        if step is None:
            return np.asarray(self.spline(self.params))
        n = max(2, int(math.ceil(self.length / float(step))) + 1)
        return np.asarray(self.spline(np.linspace(0.0, 1.0, n)))

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {f.name: getattr(self, f.name) for f in fields(self)}
        for k in ("knots", "control", "params"):
            d[k] = np.asarray(d[k]).tolist()
        return d

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SmoothPath:
        kw = dict(d)
        for k in ("knots", "control", "params"):
            kw[k] = np.asarray(kw[k], dtype=np.float64)
        return cls(**kw)


def _samples(spl: BSpline, max_deviation: float) -> tuple[FloatArray, FloatArray]:
    """Parameters whose consecutive pieces deviate from their chords by at most
    ``max_deviation``, and the bound ``e`` per piece (module docstring)."""
    d2 = spl.derivative(2) if spl.k >= 2 else None
    knots = np.unique(spl.t[(spl.t >= 0.0) & (spl.t <= 1.0)])
    if d2 is None:  # a polyline: its pieces are its chords
        return knots, np.zeros(len(knots) - 1)
    M = np.linalg.norm(np.asarray(d2(knots)), axis=1)
    # s'' is linear on a span, so |s''| <= max of its ends on every sub-interval of the span
    h = np.diff(knots)
    Mspan = np.maximum(M[:-1], M[1:])
    pieces = np.maximum(1, np.ceil(h * np.sqrt(Mspan / (8.0 * max_deviation)))).astype(np.int64)
    if pieces.sum() > MAX_PIECES:
        raise ValueError(f"the curve needs {pieces.sum():,} checked pieces (> {MAX_PIECES:,})")
    u = [knots[:1]]
    for a, b, n in zip(knots[:-1], knots[1:], pieces, strict=True):
        u.append(a + (b - a) * np.arange(1, n + 1) / n)
    params = np.concatenate(u)
    params[-1] = 1.0
    Mp = np.linalg.norm(np.asarray(d2(params)), axis=1)
    # the sub-interval's own ends bound |s''| on it (both lie in one span)
    e = np.diff(params) ** 2 / 8.0 * np.maximum(Mp[:-1], Mp[1:])
    return params, e


def smooth_path(
    points: ArrayLike,
    obstacle: PathObstacle,
    clearance: float,
    *,
    max_deviation: float = MAX_DEVIATION,
    alpha: float = 0.5,
) -> SmoothPath:
    """Fit the C2 cubic B-spline through ``points (n, d)`` and check it (module docstring).

    Parameters
    ----------
    points
        A collision-free polyline (mm), e.g. :func:`weldplan.weld.refine.refine_path`'s; fit
        it with some slack (``margin=`` there) so the curve can round its corners.
    obstacle
        Any :class:`~weldplan.geometry.pathcore.PathObstacle`; in 3D a
        :class:`~weldplan.geometry.collision.CollisionModel`, whose ``segments_free`` decides
        grazing pieces with python-fcl.
    clearance
        The radius (mm) the curve must keep.
    max_deviation
        Largest deviation (mm) of the curve from a checked chord (:data:`MAX_DEVIATION`).
    alpha
        Parameterisation exponent (0.5 centripetal, 1 chord length).

    Returns
    -------
    SmoothPath
        ``free=False`` (with the first failing piece in ``status``) when the curve does not
        keep the clearance; the caller keeps the polyline then.
    """
    P = as_path(points)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(P, axis=0), axis=1) > 0])
    P = P[keep]
    if len(P) < 2:
        raise ValueError("a smooth path needs two distinct points")
    if not (math.isfinite(max_deviation) and max_deviation > 0):
        raise ValueError(f"max_deviation must be > 0 mm, got {max_deviation!r}")
    spl = interpolating_bspline(P, alpha=alpha)
    u, e = _samples(spl, float(max_deviation))
    S = np.asarray(spl(u))
    S[0], S[-1] = P[0], P[-1]
    # one batch per distinct radius would cost one call per piece: check at the largest bound
    # per group of bounds rounded up to max_deviation / 8 (still never below the bound itself)
    quantum = max_deviation / 8.0
    radii = clearance + np.ceil(e / quantum) * quantum
    ok = np.ones(len(e), dtype=bool)
    for r in np.unique(radii):
        sel = np.flatnonzero(radii == r)
        ok[sel] = obstacle.segments_free(S[sel], S[sel + 1], float(r))
    d1 = np.asarray(spl.derivative(1)(u)) if spl.k >= 1 else np.zeros_like(S)
    d2 = np.asarray(spl.derivative(2)(u)) if spl.k >= 2 else np.zeros_like(S)
    kappa = curvature(d1, d2)
    dist = np.asarray(obstacle.distance(S), dtype=np.float64)
    free = bool(ok.all())
    status = (
        f"C2 cubic through {len(P)} points, {len(e)} pieces checked at clearance + <= "
        f"{float(e.max(initial=0.0)):.3g} mm"
    )
    if not free:
        k = int(np.flatnonzero(~ok)[0])
        status = f"piece {k} of {len(e)} (near {np.round(S[k], 3).tolist()}) leaves the clearance"
        log.debug("smooth_path: %s", status)
    return SmoothPath(
        knots=np.asarray(spl.t),
        control=np.asarray(spl.c),
        degree=int(spl.k),
        params=u,
        length=polyline_length(S),
        max_curvature=float(kappa.max(initial=0.0)),
        min_clearance=float(dist.min(initial=math.inf)),
        max_deviation=float(e.max(initial=0.0)),
        free=free,
        status=status,
    )
