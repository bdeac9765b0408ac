"""The smooth legs of a route in the robot posts (:mod:`weldplan.io.export`): header lines, and
which waypoints a KRL program may pass as ``SPL`` points of a ``SPLINE`` block.

A leg smoothed by :mod:`weldplan.weld.smoothing` carries dense waypoints on its C2 curve; every
chord between them was checked at the clearance (and is re-checked by ``weldplan verify``), so
linear moves along them (RAPID ``MoveL``, KRL ``LIN``) stay in the checked corridor. A KRL
``SPLINE`` block makes the controller interpolate its own spline through the waypoints, which
bulges off each chord toward the outside of a bend by about the sagitta ``h^2 kappa / 8`` of the
circle through the chord's neighbours (chord ``h``, curvature ``kappa``). :func:`spline_rows`
writes a leg as a block only where that circle estimate (:func:`arc_estimate`) is free at the
clearance (python-fcl), else as ``LIN`` moves. It is an estimate of the controller's curve, not
a proof; ``render_krl(smooth="lin")`` writes the checked chords only.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.weld.route import Route

__all__ = ["arc_estimate", "krl_smooth_note", "smooth_header", "spline_rows"]

#: chords of the circle estimate per chord between waypoints (:func:`arc_estimate`)
ARC_PIECES = 4
#: mm added to the clearance when the estimate is checked
ESTIMATE_MARGIN = 1e-3


def smooth_header(route: Route, rows: list[dict[str, Any]], lead: str, how: str) -> list[str]:
    """Header lines on the smooth legs of ``route`` (none when it has none)."""
    if not route.has_smooth:
        return []
    n = sum(leg.smooth is not None for leg in route.legs)
    m = sum(r["kind"] == "smooth" for r in rows)
    return [
        f"{lead}Smooth: {n} of {len(route.legs)} legs follow their C2 curve through {m} dense",
        f"{lead}waypoints, every chord between them checked at the clearance; here as",
        f"{lead}{how}.",
    ]


def krl_smooth_note(smooth: str, spl: NDArray[np.bool_]) -> str:
    if smooth == "lin":
        return "LIN moves along the checked chords"
    return f"{int(spl.sum())} SPL points in SPLINE blocks, the other smooth waypoints LIN moves"


def spline_rows(rows: list[dict[str, Any]], part: Any, clearance: float) -> NDArray[np.bool_]:
    """``(n,) bool``: the rows written as ``SPL`` points (:func:`weldplan.io.export.render_krl`):
    each run of ``smooth`` rows and the via that ends it, where the estimate of the controller's
    curve (:func:`arc_estimate`) is free at the clearance (python-fcl)."""
    from weldplan.geometry.collision import CollisionModel

    kind = [r["kind"] for r in rows]
    out = np.zeros(len(rows), dtype=bool)
    P = np.array([[float(r[k]) for k in ("x", "y", "z")] for r in rows]).reshape(-1, 3)
    model = getattr(part, "collision", part)
    if not isinstance(model, CollisionModel):
        model = CollisionModel(getattr(part, "part", part))
    k = 0
    while k < len(rows):
        if kind[k] != "smooth":
            k += 1
            continue
        j = k
        while j < len(rows) and kind[j] == "smooth":
            j += 1
        # rows k - 1 (a virtual joint) .. j (the other) are the curve's waypoints
        A = arc_estimate(P[k - 1 : j + 1])
        r = clearance + ESTIMATE_MARGIN
        out[k : j + 1] = bool(model.segments_free(A[:-1], A[1:], r, method="fcl").all())
        k = j + 1
    return out


def arc_estimate(Q: NDArray[np.float64], pieces: int = ARC_PIECES) -> NDArray[np.float64]:
    """A polyline ``(pieces (n - 1) + 1, 3)`` following the estimate of a spline through the
    points ``Q (n, 3)``: each chord replaced by ``pieces`` chords of the circle through it and
    its neighbour on the side that bends more (the chord itself where the three points are
    collinear). A spline through dense samples of a smooth curve bends like its osculating
    circles; this is an estimate of the controller's interpolation, not its formula."""
    n = len(Q)
    if n < 3:
        return Q.copy()
    out = [Q[:1]]
    t = np.arange(1, pieces + 1, dtype=np.float64)[:, None] / pieces
    for i in range(n - 1):
        a, b = Q[i], Q[i + 1]
        cands = [(Q[i - 1], a, b)] if i > 0 else []
        if i + 2 < n:
            cands.append((a, b, Q[i + 2]))
        best = max(cands, key=lambda abc: _curvature3(*abc))
        L = a + t * (b - a)
        centre = _circumcentre(*best)
        if centre is None:
            out.append(L)
            continue
        R = np.linalg.norm(a - centre)
        d = L - centre
        arc = centre + R * d / np.linalg.norm(d, axis=1, keepdims=True)
        arc[-1] = b
        out.append(arc)
    return np.concatenate(out)


def _curvature3(a: NDArray, b: NDArray, c: NDArray) -> float:
    """Curvature (1/mm) of the circle through three points (0 when collinear)."""
    den = np.linalg.norm(b - a) * np.linalg.norm(c - b) * np.linalg.norm(c - a)
    return 0.0 if den == 0 else float(2.0 * np.linalg.norm(np.cross(b - a, c - a)) / den)


def _circumcentre(a: NDArray, b: NDArray, c: NDArray) -> NDArray | None:
    """Centre of the circle through three points in R^3; None when (nearly) collinear."""
    u, v = b - a, c - a
    w = np.cross(u, v)
    w2 = float(w @ w)
    if w2 <= 1e-12 * float(u @ u) * float(v @ v):
        return None
    return a + (float(u @ u) * np.cross(v, w) + float(v @ v) * np.cross(w, u)) / (2.0 * w2)
