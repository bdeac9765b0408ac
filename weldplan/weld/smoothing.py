"""Smooth legs for a route: a C2 curve between the virtual joints of each leg, exported as dense
waypoints whose every chord is checked at the clearance (issue 15 item 2; ``weldplan plan
--smooth``).

For each leg of a :class:`~weldplan.weld.route.Route` the part between its two virtual joints
(the refined polyline: the approach segments to the weld spots stay straight, they are the
verifier's cones) goes through :func:`weldplan.geometry.smooth.smooth_path`: the C2 cubic
through its vertices, checked on a sampling that is conservative by construction (the curve's
deviation from each checked chord is bounded exactly and added to the radius). The refinement
leaves vertices on the clearance surface (``clearance + 0.01`` mm), so the first bound
(:data:`DEVIATIONS`, 0.05 mm) often asks more room than the curve has; the check is repeated
with finer pieces (smaller bounds) before the curve is given up. Both the chord-length and the
centripetal parameterisation are tried (:data:`ALPHAS`) and the free curve of least maximum
curvature is kept.

A curve that passes is sampled by arc length every ``spacing`` mm (:data:`SMOOTH_SPACING`), and
the chords between the samples are what leaves weldplan: a robot moves along them (RAPID
``MoveL``) or through them (KRL ``SPL``). A chord cuts a bend by up to ``h^2 kappa / 8`` toward
its inside, where the obstacle is, so each chord is checked again with python-fcl at the
clearance (plus :data:`CHORD_MARGIN`, so the independent check of
:func:`weldplan.weld.verify.verify_route` is not decided by rounding), and a chord that fails is
split at its curve parameter midpoint, up to :data:`CHORD_SPLITS` times. ``spacing`` is thus the
largest spacing; the waypoints are denser where the curve hugs the clearance around a bend.

A leg whose curve fails (or whose chords still fail after the splits) keeps its polyline, and
``Route.stats["smooth"]["legs"]`` says why: nothing is repaired silently. A leg whose middle is
one straight segment has nothing to smooth and keeps it.

Deviation from the issue's wording: the curve is not fitted through the weld spots. The approach
segments are checked as cones (:mod:`weldplan.weld.verify`), which only a straight descent onto
the spot satisfies, so the curve runs from virtual joint to virtual joint and meets each
approach at a corner (where the torch is at the approach point of a weld anyway).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.geometry.pathcore import arc_lengths, pieces_for, polyline_length
from weldplan.geometry.smooth import SmoothPath, smooth_path
from weldplan.weld.route import Leg, Route
from weldplan.weld.validate import positive_mm

log = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

__all__ = [
    "ALPHAS",
    "CHORD_MARGIN",
    "CHORD_SPLITS",
    "DEVIATIONS",
    "SMOOTH_SPACING",
    "LegSmoothing",
    "dense_waypoints",
    "smooth_leg",
    "smooth_route",
]

#: mm: the largest spacing of the dense waypoints along the curve (arc length)
SMOOTH_SPACING = 5.0
#: mm: the bounds on the curve's deviation from its checked chords, tried in turn
#: (:func:`weldplan.geometry.smooth.smooth_path` ``max_deviation``); a finer bound costs more
#: pieces (about ``1 / sqrt``) but asks less room than the refinement's 0.01 mm margin
DEVIATIONS = (0.05, 0.01, 0.002)
#: parameter exponents of the curve tried (1 chord length, 0.5 centripetal); the free curve of
#: least maximum curvature is kept. The centripetal curve avoids overshoot at uneven spacing but
#: kinks at the refinement's very short segments (a 0.14 mm segment on car2_50: radius 0.4 mm
#: centripetal, 11 mm chord length)
ALPHAS = (1.0, 0.5)
#: mm added to the clearance when the exported chords are checked, so the verifier's check at
#: the clearance is not decided by rounding
CHORD_MARGIN = 1e-3
#: times a failing chord is split at its curve parameter midpoint before the leg gives up
CHORD_SPLITS = 6


@dataclass(frozen=True)
class LegSmoothing:
    """What the smoothing did to one leg (``Route.stats["smooth"]["legs"]``).

    Attributes
    ----------
    leg, from_id, to_id
        Which leg.
    smoothed
        The leg carries a smooth path (:attr:`weldplan.weld.route.Leg.smooth`).
    curved
        Its polyline bends between the virtual joints (False: one straight segment, nothing to
        smooth).
    polyline_length
        mm between the virtual joints along the polyline.
    length
        mm along the C2 curve (its checked sampling); ``nan`` when no curve passed.
    waypoints_length
        mm along the exported dense waypoints (chords: a little shorter than the curve).
    waypoints
        Number of dense waypoints between the virtual joints (both included).
    max_curvature
        1/mm, the largest curvature of the curve (``0`` for a straight middle).
    min_clearance
        mm, the smallest distance from the curve's samples to the part (``nan`` when unknown).
    max_deviation
        mm, the bound the curve was checked with (it is free at ``clearance + max_deviation``).
    status
        One line: how it went, or why the polyline was kept.
    """

    leg: int
    from_id: str
    to_id: str
    smoothed: bool
    curved: bool
    polyline_length: float
    length: float = math.nan
    waypoints_length: float = math.nan
    waypoints: int = 0
    max_curvature: float = 0.0
    min_clearance: float = math.nan
    max_deviation: float = math.nan
    status: str = ""

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def dense_waypoints(sp: SmoothPath, spacing: float) -> tuple[FloatArray, FloatArray]:
    """Parameters ``(n,)`` and points ``(n, d)`` of ``sp`` every ``spacing`` mm of arc length
    (at most; measured on the curve's checked sampling), both ends exact."""
    spl = sp.spline
    S = np.asarray(spl(sp.params))
    s = arc_lengths(S)
    n = pieces_for(s[-1], spacing)
    u = np.interp(np.linspace(0.0, s[-1], n + 1), s, sp.params)
    u[0], u[-1] = 0.0, 1.0
    return u, np.asarray(spl(u))


def _checked_chords(
    sp: SmoothPath, model: Any, clearance: float, spacing: float, ends: FloatArray
) -> tuple[FloatArray | None, str]:
    """The dense waypoints of ``sp`` whose chords are free at ``clearance + CHORD_MARGIN``
    (python-fcl), splitting the failing chords (module docstring); ``None`` and why if some
    chord still fails."""
    spl = sp.spline
    u, W = dense_waypoints(sp, spacing)
    W[0], W[-1] = ends
    r = clearance + CHORD_MARGIN
    for _ in range(CHORD_SPLITS + 1):
        ok = np.asarray(model.segments_free(W[:-1], W[1:], r, method="fcl"), dtype=bool)
        if ok.all():
            return W, ""
        bad = np.flatnonzero(~ok)
        mid = 0.5 * (u[bad] + u[bad + 1])
        u = np.insert(u, bad + 1, mid)
        W = np.insert(W, bad + 1, np.asarray(spl(mid)), axis=0)
    k = int(np.flatnonzero(~ok)[0])
    return None, (
        f"chord {k} of the dense waypoints (near {np.round(W[k], 3).tolist()}) fails at "
        f"{clearance:g} mm after {CHORD_SPLITS} splits: polyline kept"
    )


def _checked_curve(mid: FloatArray, model: Any, clearance: float, alpha: float) -> SmoothPath:
    """The curve of parameter exponent ``alpha`` through ``mid``, checked with the bounds of
    :data:`DEVIATIONS` in turn until it passes (the last one tried when none does)."""
    for dev in DEVIATIONS:
        sp = smooth_path(mid, model, clearance, max_deviation=dev, alpha=alpha)
        if sp.free:
            break
    return sp


def _least_curved(mid: FloatArray, model: Any, clearance: float) -> SmoothPath | str:
    """Of the curves of :data:`ALPHAS` that pass their check, the one of least maximum
    curvature; else the first that failed (its status says where); a string when no curve could
    be built at all."""
    best: SmoothPath | None = None
    failed: SmoothPath | None = None
    for alpha in ALPHAS:
        try:
            sp = _checked_curve(mid, model, clearance, alpha)
        except ValueError as exc:  # too many pieces: a wild curve
            return f"no curve: {exc}: polyline kept"
        if not sp.free:
            failed = failed or sp
        elif best is None or sp.max_curvature < best.max_curvature:
            best = sp
    out = best or failed
    assert out is not None
    return out


def smooth_leg(
    mid: FloatArray, model: Any, clearance: float, spacing: float = SMOOTH_SPACING
) -> tuple[FloatArray | None, dict[str, Any]]:
    """Smooth the path between the virtual joints of one leg (module docstring).

    Parameters
    ----------
    mid
        ``(n, 3)`` mm: the leg's polyline from virtual joint to virtual joint, free at
        ``clearance``.
    model
        The part's :class:`~weldplan.geometry.collision.CollisionModel`.
    clearance
        mm, the torch-tip radius.
    spacing
        mm, the largest spacing of the dense waypoints.

    Returns
    -------
    waypoints, figures
        ``(m, 3)`` dense waypoints from ``mid[0]`` to ``mid[-1]`` (exactly), or ``None`` when the
        polyline is kept; the :class:`LegSmoothing` fields other than the leg's identity.
    """
    L = polyline_length(mid)
    fig: dict[str, Any] = {"smoothed": False, "curved": len(mid) > 2, "polyline_length": L}
    if len(mid) < 3:
        fig.update(status="straight between its virtual joints: nothing to smooth")
        return None, fig
    sp = _least_curved(mid, model, clearance)
    if isinstance(sp, str):
        fig.update(status=sp)
        return None, fig
    fig.update(
        length=sp.length,
        max_curvature=sp.max_curvature,
        min_clearance=sp.min_clearance,
        max_deviation=sp.max_deviation,
    )
    if not sp.free:
        fig.update(status=f"the curve fails its check ({sp.status}): polyline kept")
        return None, fig
    W, why = _checked_chords(sp, model, clearance, spacing, mid[[0, -1]])
    if W is None:
        fig.update(status=why)
        return None, fig
    fig.update(
        smoothed=True,
        waypoints=len(W),
        waypoints_length=polyline_length(W),
        status=f"C2 curve free at {clearance:g} + {sp.max_deviation:.3g} mm, {len(W)} waypoints "
        f"with chords free at {clearance:g} mm",
    )
    return W, fig


def _middle(route: Route, k: int) -> tuple[int, int]:
    """``a, b``: the leg's points ``[a:b]`` run from virtual joint to virtual joint."""
    leg = route.legs[k]
    start, end = route.approach_flags(k)
    return (1 if start else 0), (len(leg.points) - 1 if end else len(leg.points))


def smooth_route(
    route: Route, part: Any, *, spacing: float = SMOOTH_SPACING, clearance: float | None = None
) -> Route:
    """``route`` with a smooth path on every leg whose curve passes (module docstring).

    Parameters
    ----------
    route
        A planned route (its legs' polylines free at the clearance).
    part
        The cell (``.collision``) or the part's
        :class:`~weldplan.geometry.collision.CollisionModel`.
    spacing
        mm, the largest spacing of the dense waypoints (:data:`SMOOTH_SPACING`).
    clearance
        mm; default the route's own (``route.settings["clearance"]``).

    Returns
    -------
    Route
        The same route with :attr:`~weldplan.weld.route.Leg.smooth` set where smoothed, and
        ``stats["smooth"]``: ``spacing``, ``legs`` (one :class:`LegSmoothing` dict per leg),
        ``smoothed``, ``curved`` (legs with a bend to smooth), ``max_curvature`` (1/mm) and
        ``min_clearance_margin`` (mm over the clearance) over the smoothed legs,
        ``length`` (mm along the smooth paths, polyline where not smoothed) and ``seconds``.
    """
    t0 = time.perf_counter()
    spacing = positive_mm("spacing", spacing)  # a ConfigError (a ValueError) naming it
    model = getattr(part, "collision", part)
    c = float(route.settings.get("clearance", 5.0) if clearance is None else clearance)
    legs: list[Leg] = []
    figures: list[LegSmoothing] = []
    for k, leg in enumerate(route.legs):
        a, b = _middle(route, k)
        W, fig = smooth_leg(leg.points[a:b], model, c, float(spacing))
        figures.append(LegSmoothing(k, leg.from_id, leg.to_id, **fig))
        if W is None:
            legs.append(dataclasses.replace(leg, smooth=None))
            if len(leg.points[a:b]) > 2:
                log.info("leg %d (%s -> %s): %s", k, leg.from_id, leg.to_id, fig["status"])
            continue
        path = np.concatenate([leg.points[:a], W, leg.points[b:]])
        legs.append(dataclasses.replace(leg, smooth=path))
    done = [f for f in figures if f.smoothed]
    stats = dict(route.stats)
    stats["smooth"] = {
        "spacing": float(spacing),
        "clearance": c,
        "legs": [f.to_dict() for f in figures],
        "smoothed": len(done),
        "curved": sum(f.curved for f in figures),
        "max_curvature": max((f.max_curvature for f in done), default=0.0),
        "min_clearance_margin": min((f.min_clearance - c for f in done), default=math.nan),
        "length": float(sum(leg.smooth_length for leg in legs)),
        "seconds": time.perf_counter() - t0,
    }
    out = dataclasses.replace(route, legs=tuple(legs), stats=stats)
    log.info(
        "smoothed %d of %d curved legs in %.2f s", len(done), stats["smooth"]["curved"],
        stats["smooth"]["seconds"],
    )  # fmt: skip
    return out
