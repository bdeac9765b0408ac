"""Corner blending for robot programs: the largest zone each fly-by point may have.

A robot controller does not pass through a fly-by point: within a zone of radius ``r`` around
the programmed corner ``P`` it leaves the incoming segment and joins the outgoing one on a
corner-cutting curve (ABB RAPID ``zonedata``, KUKA KRL ``C_DIS`` with ``$APO.CDIS``). That curve
starts and ends on the segments within ``r`` of ``P`` and stays in the convex hull of its entry
point, ``P`` and its exit point, so every point ``q`` of it satisfies ``|q - P| <= r``. The
route was verified segment by segment at the clearance ``c``; the blend is not on those
segments, so it is checked here:

* free margin of a corner: ``m(P) = d(P) - c - tol``, with ``d(P)`` the exact distance from
  ``P`` to the part's triangles (open3d, see :class:`~weldplan.geometry.distance.SurfaceDistance`)
  and ``tol`` its single-precision round-off bound. For any ``q`` with ``|q - P| <= r <= m(P)``,
  ``d(q) >= d(P) - r >= c``: the torch-tip sphere stays clear everywhere on the blend.
* :data:`ROUNDING_MM` is taken off the margin for the 0.001 mm rounding of the written points;
* the radius is also capped at half of each adjacent segment, so that neighbouring zones never
  overlap (controllers shrink overlapping zones on their own; weldplan does not rely on it).

The allowed radius is ``min(m(P), |P - A| / 2, |B - P| / 2)`` (``A``, ``B`` the neighbours),
never more than the program's maximum zone. Weld spots, the first point (the approach after a
joint move from anywhere) and the last point (the retreat) are exact stops.

Deviation worth naming: the distance is unsigned. A corner inside a closed solid would look free;
the corners come from a route that passed :func:`~weldplan.weld.verify.verify_route`, whose job
it is to reject such a route before it is exported.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import WeldplanError

log = logging.getLogger(__name__)

#: ABB's predefined ``zonedata`` (RAPID reference manual, "zonedata"): name -> TCP path zone
#: radius ``pzone_tcp`` in mm. ``z0`` is 0.3 mm, not 0; ``fine`` is an exact stop.
RAPID_ZONES: dict[str, float] = {
    "z0": 0.3,
    "z1": 1.0,
    "z5": 5.0,
    "z10": 10.0,
    "z15": 15.0,
    "z20": 20.0,
    "z30": 30.0,
    "z40": 40.0,
    "z50": 50.0,
    "z60": 60.0,
    "z80": 80.0,
    "z100": 100.0,
    "z150": 150.0,
    "z200": 200.0,
}

#: mm taken off every margin for the programs' rounding: they write coordinates to 0.001 mm, so
#: a written corner lies within ``0.0005 * sqrt(3) = 0.00087`` mm of the checked one
ROUNDING_MM = 1e-3

#: KRL ``$APO.CDIS`` values are written rounded *down* to this step (mm); smaller radii are exact
#: stops (a 0.05 mm approximation gains nothing)
CDIS_STEP = 0.1


def _distance_function(part: Any) -> Any:
    """Point-to-surface distance of ``part``: a CollisionModel, a Cell or a trimesh.Trimesh.

    Raises :class:`WeldplanError` when ``part`` is missing or of another type.
    """
    from weldplan.geometry.collision import CollisionModel
    from weldplan.geometry.distance import SurfaceDistance

    if part is None:
        raise WeldplanError(
            "robot posts need the part (a mesh, cell or CollisionModel) to check each corner's "
            "blend zone against the clearance: render_post(route, post, part=...)"
        )
    model = getattr(part, "collision", part)  # a Cell carries its CollisionModel
    if isinstance(model, CollisionModel):
        return model.distance
    mesh = getattr(part, "part", part)
    if isinstance(mesh, trimesh.Trimesh):
        return SurfaceDistance(mesh)
    raise WeldplanError(
        f"part must be a trimesh.Trimesh, a Cell or a CollisionModel, got {type(part).__name__}"
    )


def route_clearance(route: Any, clearance: float | None = None) -> float:
    """The clearance (mm) the blends must keep: ``clearance`` or the route's own setting."""
    c = clearance if clearance is not None else (route.settings or {}).get("clearance")
    try:
        c = float(c)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        c = math.nan
    if not (math.isfinite(c) and c > 0):
        raise WeldplanError(
            f"robot posts need a positive finite clearance to choose blend zones, got {c} "
            "(the route's settings carry none: pass clearance=)"
        )
    return c


def allowed_radii(
    points: ArrayLike, blend: ArrayLike, part: Any, clearance: float
) -> NDArray[np.float64]:
    """``(n,) float``: the largest blend radius (mm) each program point may have.

    Parameters
    ----------
    points
        ``(n, 3)`` programmed points in travel order (mm).
    blend
        ``(n,) bool``: which points are candidates for fly-by (others get 0).
    part
        The part: a trimesh.Trimesh, a Cell or a CollisionModel.
    clearance
        Torch-tip radius (mm) the route was verified at.

    Returns
    -------
    ``min(d(P) - clearance - tol - ROUNDING_MM, |P - A| / 2, |B - P| / 2)`` clipped at 0
    (module docstring);
    0 for the first and last point and wherever ``blend`` is false.
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    mask = np.asarray(blend, dtype=bool).copy()
    n = len(P)
    out = np.zeros(n)
    if n < 3:
        return out
    mask[[0, -1]] = False
    idx = np.flatnonzero(mask)
    if len(idx) == 0:
        return out
    dist = _distance_function(part)
    free = dist(P[idx]) - clearance - dist.tolerance - ROUNDING_MM
    seg = np.linalg.norm(np.diff(P, axis=0), axis=1)  # (n - 1,)
    half = 0.5 * np.minimum(seg[idx - 1], seg[idx])
    out[idx] = np.maximum(np.minimum(free, half), 0.0)
    out[~np.isfinite(out)] = 0.0
    return out


def rapid_zone(radius: float, max_zone: str = "z5") -> str:
    """The largest predefined ``zonedata`` whose radius is ``<= radius`` and ``<= max_zone``'s,
    else ``"fine"``."""
    if max_zone == "fine":
        return "fine"
    if max_zone not in RAPID_ZONES:
        raise WeldplanError(
            f"zone must be 'fine' or one of {', '.join(RAPID_ZONES)}, got {max_zone!r}"
        )
    cap = min(radius, RAPID_ZONES[max_zone])
    best = "fine"
    for name, r in RAPID_ZONES.items():
        if r <= cap:
            best = name
    return best


def krl_cdis(radius: float, max_cdis: float = 5.0) -> float:
    """The ``$APO.CDIS`` (mm) for a corner whose allowed radius is ``radius``: rounded down to
    :data:`CDIS_STEP` and capped at ``max_cdis``; 0 means an exact stop (no ``C_DIS``)."""
    if not (math.isfinite(max_cdis) and max_cdis >= 0):
        raise WeldplanError(f"cdis must be a finite value >= 0 mm, got {max_cdis}")
    r = min(radius, max_cdis)
    steps = math.floor(r / CDIS_STEP + 1e-9)
    v = round(steps * CDIS_STEP, 6)
    return v if v <= r else max(v - CDIS_STEP, 0.0)
