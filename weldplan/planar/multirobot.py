"""Several robots (paper 001, section 3): the expansion logic strategy and the scoring function.

This module holds the paper's building blocks; the time-stepped simulation of three robots
following their HAFSA paths is not written yet (see the project notes).

Expansion logic (001 eqs. 12-14): for a polygonal obstacle with vertices ``p_i``, the vertex
pair at the largest distance ``d_max = max d_ij`` (eq. 13) defines a range circle centred on
their midpoint with diameter ``d_max`` (eq. 14, the "endpoint connection method", chosen by
the paper over the minimum circumscribed circle for speed). Two concentric circles of diameter
``1.2 d_max`` and ``1.4 d_max`` follow; the collision probability is 0.85 inside the first
circle (outside the obstacle), 0.65 between it and the 1.2 circle, 0.45 between the 1.2 and
1.4 circles. We take it as 1 inside the obstacle and 0 beyond the last circle (the paper does
not say).

Scoring (001 eq. 15): ``score = 100 - ceil(dist / l)`` with ``dist`` the start-to-goal
distance and ``l`` the start-to-current-position distance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: diameters of the expansion circles as multiples of d_max (001 sec. 3)
EXPANSION_FACTORS = (1.0, 1.2, 1.4)
#: collision probabilities in the three rings (001 sec. 3)
COLLISION_PROBABILITIES = (0.85, 0.65, 0.45)
#: the top score of eq. 15
SCORE_TOP = 100


@dataclass(frozen=True)
class ExpansionZone:
    """The expansion circles of one polygonal obstacle.

    Attributes
    ----------
    center
        ``(2,)``: midpoint of the farthest vertex pair (eq. 14).
    d_max
        Largest vertex-to-vertex distance (eq. 13).
    radii
        ``(3,)``: radii of the circles of diameter ``d_max``, ``1.2 d_max``, ``1.4 d_max``.
    vertices
        ``(n, 2)``: the obstacle.
    """

    center: tuple[float, float]
    d_max: float
    radii: tuple[float, float, float]
    vertices: tuple[tuple[float, float], ...]


def expansion_zone(vertices: ArrayLike) -> ExpansionZone:
    """The expansion circles of the polygon ``vertices (n, 2)`` (001 eqs. 12-14)."""
    V = np.asarray(vertices, dtype=np.float64).reshape(-1, 2)
    if len(V) < 2:
        raise ValueError("an obstacle needs at least two vertices")
    d = np.linalg.norm(V[:, None] - V[None], axis=-1)  # eq. 12
    i, j = np.unravel_index(int(np.argmax(d)), d.shape)
    d_max = float(d[i, j])  # eq. 13
    c = 0.5 * (V[i] + V[j])  # eq. 14
    radii = tuple(0.5 * f * d_max for f in EXPANSION_FACTORS)
    return ExpansionZone(
        center=(float(c[0]), float(c[1])),
        d_max=d_max,
        radii=(float(radii[0]), float(radii[1]), float(radii[2])),
        vertices=tuple((float(x), float(y)) for x, y in V),
    )


def collision_probability(zones: list[ExpansionZone], points: ArrayLike) -> NDArray[np.float64]:
    """Collision probability ``(...)`` of points ``(..., 2)``: the largest over the zones of
    1 inside the obstacle, 0.85 / 0.65 / 0.45 in the three rings, 0 outside them."""
    from matplotlib.path import Path as MplPath

    P = np.asarray(points, dtype=np.float64)
    flat = P.reshape(-1, 2)
    out = np.zeros(len(flat))
    for z in zones:
        r = np.linalg.norm(flat - np.asarray(z.center), axis=1)
        p = np.select(
            [r <= z.radii[0], r <= z.radii[1], r <= z.radii[2]],
            list(COLLISION_PROBABILITIES),
            0.0,
        )
        inside = MplPath(np.asarray(z.vertices)).contains_points(flat)
        p[inside] = 1.0
        out = np.maximum(out, p)
    return out.reshape(P.shape[:-1])


def score(dist: ArrayLike, l: ArrayLike) -> NDArray[np.int64]:  # noqa: E741 - the paper's name
    """001 eq. 15: ``100 - ceil(dist / l)`` (``l > 0``)."""
    d = np.asarray(dist, dtype=np.float64)
    ll = np.asarray(l, dtype=np.float64)
    if np.any(ll <= 0):
        raise ValueError("l (distance from the start to the current position) must be > 0")
    return (SCORE_TOP - np.ceil(d / ll - 1e-12)).astype(np.int64)
