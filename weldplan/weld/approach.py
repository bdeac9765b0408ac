"""The approach cone of a weld spot: the capsules that check the segment ``spot -> virtual
joint`` (:mod:`weldplan.weld.verify`'s module docstring derives the cone), and the depth of a spot
below the surface it is approached through (``spot_depth``: a spot on the faying surface of a
sheet stack). The route check (:func:`weldplan.weld.verify.verify_route`) and the virtual-joint
search (:func:`weldplan.weld.cell.build_cell`) use the same cone."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from weldplan.errors import InputError
from weldplan.geometry.collision import CollisionModel
from weldplan.weld.route import Route

#: capsules per approach segment (the cone of the module docstring, inscribed)
APPROACH_PIECES = 8
#: mm next to the weld spot that are not checked (the torch is at the weld there)
APPROACH_EXEMPT_MM = 0.5
#: relative slack on the approach-cone radius, so contact at exact equality is not a collision
APPROACH_SLACK = 1e-3


def approach_pieces(
    spot: NDArray[np.float64],
    virtual: NDArray[np.float64],
    clearance: float,
    *,
    pieces: int = APPROACH_PIECES,
    exempt: float = APPROACH_EXEMPT_MM,
    depth: float = 0.0,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The capsules that check the approach ``spot -> virtual`` (module docstring).

    ``depth`` (mm, >= 0) is how far below the surface the spot lies along its approach (a spot
    on the faying surface of a sheet stack: the gauge of the sheet the gun presses, plus the
    gap): the cone's apex moves out along the approach by ``depth``, so the first
    ``depth + exempt`` mm are not checked and the radius grows from 0 at the apex,
    ``clearance * (s - depth) / (L - depth)``. ``depth = 0`` is the spot on the surface.

    Returns
    -------
    A, B
        ``(m, 3)`` capsule ends in mm (``m = pieces``, or 0 when the approach is shorter than
        ``exempt``).
    radii
        ``(m,)`` capsule radii in mm, ``clearance * s_m / L * (1 - APPROACH_SLACK)``.
    """
    spot = np.asarray(spot, dtype=float)
    virtual = np.asarray(virtual, dtype=float)
    d = virtual - spot
    L = float(np.linalg.norm(d))
    if L <= exempt + depth:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    s = np.linspace(exempt + depth, L, pieces + 1)
    pts = spot + np.outer(s / L, d)
    radii = clearance * (s[:-1] - depth) / (L - depth) * (1.0 - APPROACH_SLACK)
    return pts[:-1], pts[1:], radii


def approach_free(
    model: CollisionModel,
    spot: NDArray[np.float64],
    virtual: NDArray[np.float64],
    clearance: float,
    *,
    pieces: int = APPROACH_PIECES,
    depth: float = 0.0,
) -> bool:
    """Whether the approach ``spot -> virtual`` stays within its cone (module docstring): the
    check :func:`verify_route` makes, for one approach (``depth``: :func:`approach_pieces`)."""
    A, B, r = approach_pieces(spot, virtual, clearance, pieces=pieces, depth=depth)
    return all(model.segment_free(a, b, float(rr)) for a, b, rr in zip(A, B, r, strict=True))


def spot_depth(route: Route) -> float:
    """mm below the surface the route's weld spots lie (``route.settings["spot_depth"]``, 0
    when absent: :func:`approach_pieces`)."""
    v = route.settings.get("spot_depth", 0.0)
    try:
        depth = float(v)
    except (TypeError, ValueError):
        depth = math.nan
    if not (math.isfinite(depth) and depth >= 0.0):
        raise InputError(f"the route's spot_depth must be a finite number >= 0 mm, got {v!r}")
    return depth
