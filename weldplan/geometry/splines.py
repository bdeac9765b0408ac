"""Smooth paths through nodes: cubic splines (paper 000) and clamped B-splines.

Both work on many paths at once: nodes ``(..., k, d)`` (any number of leading path axes, any
dimension ``d``: 2 for the planar maps, 3 for torch routes) give points ``(..., n, d)``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import BSpline, CubicSpline

#: interpolation points per path in paper 000 (sec. 4.4 leaves n open; 100 as in the common
#: MATLAB implementation of spline path planning that the paper's setup follows)
N_INTERP = 100


def node_parameters(k: int) -> NDArray[np.float64]:
    """The spline parameter of ``k`` nodes: uniform ``t = linspace(0, 1, k)``.

    Paper 000 interpolates x and y separately against the node index ("cubic spline
    interpolation in the x and y directions"), which is this uniform parameterisation.
    """
    return np.linspace(0.0, 1.0, int(k))


def cubic_spline_path(
    nodes: ArrayLike, n_points: int = N_INTERP, bc_type: str = "not-a-knot"
) -> NDArray[np.float64]:
    """Points of the cubic spline through ``nodes``.

    Parameters
    ----------
    nodes
        ``(..., k, d)``, k >= 2: start, path nodes, end (in order).
    n_points
        Points sampled at uniform parameter steps, including both ends.
    bc_type
        ``"not-a-knot"`` (MATLAB ``spline``'s default, used by paper 000), or any
        :class:`scipy.interpolate.CubicSpline` boundary condition.

    Returns
    -------
    ``(..., n_points, d)``: the first point is ``nodes[..., 0, :]`` and the last
    ``nodes[..., -1, :]`` exactly; every node is passed through.
    """
    N = np.asarray(nodes, dtype=np.float64)
    if N.ndim < 2 or N.shape[-2] < 2:
        raise ValueError(f"nodes must be (..., k >= 2, d), got {N.shape}")
    M = cubic_spline_matrix(N.shape[-2], int(n_points), bc_type)
    out = M @ N
    out[..., 0, :] = N[..., 0, :]
    out[..., -1, :] = N[..., -1, :]
    return out


@lru_cache(maxsize=64)
def cubic_spline_matrix(k: int, n_points: int, bc_type: str = "not-a-knot") -> NDArray:
    """The ``(n_points, k)`` matrix taking ``k`` nodes to the spline's sample points.

    A cubic spline with linear boundary conditions is linear in its data, so sampling it is
    one matrix product: ``points = M @ nodes``. Built once per ``(k, n_points)`` by
    interpolating the identity with :class:`scipy.interpolate.CubicSpline`.
    """
    tt = np.linspace(0.0, 1.0, n_points)
    if k == 2:
        M = np.stack([1.0 - tt, tt], axis=1)
    else:
        M = CubicSpline(node_parameters(k), np.eye(k), axis=0, bc_type=bc_type)(tt)
    M.setflags(write=False)
    return M


def bspline_path(control: ArrayLike, n_points: int = N_INTERP, degree: int = 3) -> NDArray:
    """Points of the clamped uniform B-spline with control points ``control (..., k, d)``.

    The curve starts at the first and ends at the last control point and stays in the convex
    hull of the control polygon (it does not pass through the inner control points). The degree
    drops to ``k - 1`` when there are too few control points.

    Returns
    -------
    ``(..., n_points, d)``.
    """
    C = np.asarray(control, dtype=np.float64)
    if C.ndim < 2 or C.shape[-2] < 2:
        raise ValueError(f"control points must be (..., k >= 2, d), got {C.shape}")
    k = C.shape[-2]
    p = min(int(degree), k - 1)
    inner = np.linspace(0.0, 1.0, k - p + 1)
    knots = np.concatenate([np.zeros(p), inner, np.ones(p)])
    Y = np.moveaxis(C, -2, 0)
    tt = np.linspace(0.0, 1.0, int(n_points))
    out = np.moveaxis(BSpline(knots, Y, p, axis=0)(tt), 0, -2)
    out[..., 0, :] = C[..., 0, :]
    out[..., -1, :] = C[..., -1, :]
    return out


def interp_spline_path(nodes: ArrayLike, n_points: int = N_INTERP, degree: int = 3) -> NDArray:
    """The interpolating B-spline of ``degree`` through ``nodes (..., k, d)`` (scipy
    ``make_interp_spline``, uniform parameter): ``(..., n_points, d)``."""
    from scipy.interpolate import make_interp_spline

    N = np.asarray(nodes, dtype=np.float64)
    k = N.shape[-2]
    p = min(int(degree), k - 1)
    Y = np.moveaxis(N, -2, 0)
    tt = np.linspace(0.0, 1.0, int(n_points))
    out = np.moveaxis(make_interp_spline(node_parameters(k), Y, k=p, axis=0)(tt), 0, -2)
    out[..., 0, :] = N[..., 0, :]
    out[..., -1, :] = N[..., -1, :]
    return out


def interpolating_bspline(points: ArrayLike, *, alpha: float = 0.5) -> BSpline:
    """The C2 cubic B-spline through the points ``(k, d)``, ``k >= 2``, with natural ends.

    The parameter of point ``i`` is the sum of ``|P[j + 1] - P[j]| ** alpha`` before it, scaled
    to ``[0, 1]``: ``alpha = 0.5`` is the centripetal parameterisation (it does not overshoot
    or loop at sharp turns the way the uniform one does), 1 the chord length. Fewer than four
    points give the straight polyline (degree 1) or a natural cubic through three.

    Returns
    -------
    scipy.interpolate.BSpline
        ``s(u)`` for ``u`` in ``[0, 1]``, ``s(0) = P[0]``, ``s(1) = P[-1]``; ``s(u_i) = P[i]``.
    """
    from scipy.interpolate import make_interp_spline

    P = np.asarray(points, dtype=np.float64)
    if P.ndim != 2 or len(P) < 2:
        raise ValueError(f"points must be (k >= 2, d), got {P.shape}")
    step = np.linalg.norm(np.diff(P, axis=0), axis=1) ** float(alpha)
    if np.any(step <= 0):
        raise ValueError("consecutive points must differ")
    u = np.concatenate([[0.0], np.cumsum(step)])
    u /= u[-1]
    if len(P) == 2:
        return make_interp_spline(u, P, k=1)
    return make_interp_spline(u, P, k=3, bc_type="natural")
