"""Flanges from the mesh: where sheets lie face to face near a free edge, and spots snapped to them.

A spot-welding gun closes on a **stack**: two (or more) sheets face to face, a small air gap
apart, over an overlap wide enough for the electrode caps, near a **free edge** the gun's C-arm
can come round (issue 29, item 3). This module finds such stacks on a part and tells, per weld
spot, which stack it sits on and what it joins, or why none.

API (what ``weldplan check-spots`` and the tests call)
------------------------------------------------------
``snap_spots(part_or_sheets, points, settings=None) -> tuple[SpotSnap, ...]``
    One frozen :class:`SpotSnap` per spot, in order: ``ok``, a ``verdict`` (:data:`VERDICTS`:
    ``"stack"``, ``"wall"``, or why not: ``"no sheet"``, ``"single skin"``, ``"too thick"``,
    ``"narrow overlap"``, ``"no free edge"``), a one-line ``reason``, the snapped ``position``
    (on the faying surface: the middle of the air gap nearest the spot), and the :class:`Stack`
    (its sheets in order along the normal, their gauges, the gaps, the stack thickness, the
    overlap width and the distance to the free edge).
``find_flanges(part_or_sheets, settings=None, *, rng=0) -> tuple[FlangePatch, ...]``
    Every stack of the part as a patch: centre, normal, bodies, gap, thickness, overlap width,
    edge distance, area.

``part_or_sheets`` is a mesh (each connected component is a sheet: what
:func:`weldplan.io.mesh.load_part` makes of a multi-body file, named ``body0, body1, ...``), a
``trimesh.Scene`` (its named geometries), a ``{name: mesh}`` mapping (e.g.
:func:`weldplan.weld.sheetmetal.read_sheets`) or a list of meshes, in mm; or a prepared
:class:`Sheets` (build it once to query many times).

How a stack is measured (vectorised: open3d ray casting in C++, numpy over all rays)
-------------------------------------------------------------------------------------
Through a point, the whole **normal line** (along the normal of the nearest sheet face) is
cast against every sheet at once (``RaycastingScene.list_intersections``). The hits of
one sheet pair up into **layers** (entry, exit: a closed sheet's two faces; a lone hit is a
zero-thickness surface sheet). Consecutive layers whose faces are parallel (within
``parallel_deg`` of the line) and at most ``max_gap`` apart form a **run**; the run nearest the
point is its stack: a ``lap`` when it holds two sheets or more, else a single skin (or, with
``walls=True`` for slab models such as car2, a ``wall`` when its one body is at most
``max_wall`` thick: a gun straddles the slab as it would the stack it models).

The **overlap** and the **edge** are measured by marching from the snapped point in
``directions`` directions in the stack's plane (every ``edge_step`` mm to 40 mm, then every
5 mm to ``edge_reach``): the stack goes on while the normal line still finds the two sheets of
the spot's faying surface face to face within ``max_gap``. The overlap width is the least
``r(d) + r(-d)`` over the directions, and the stack breaks at a **free edge** where the line then
meets no sheet at all within the stack's thickness plus ``max_gap`` of its plane (a sheet
ending, not a wall rising from the flange's root): ``edge_distance`` is the nearest such break.

Thicknesses and gaps are measured along the line, which is the sheets' normal for flat stacks,
to open3d's float32 precision (1e-4 mm on a 5 m body).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import InputError
from weldplan.geometry.stacks import FlangeSettings, Found, Sheets, find_stacks, march
from weldplan.random import RNGLike, as_generator

__all__ = [
    "FlangePatch",
    "FlangeSettings",
    "Sheets",
    "SpotSnap",
    "Stack",
    "VERDICTS",
    "find_flanges",
    "snap_spots",
]

log = logging.getLogger(__name__)

#: the verdicts of :class:`SpotSnap`; the first two are ``ok``
VERDICTS: tuple[str, ...] = (
    "stack",
    "wall",
    "no sheet",
    "single skin",
    "too thick",
    "narrow overlap",
    "no free edge",
)
#: a wall's patch normal is oriented to this side (a generic direction: no face is exactly
#: perpendicular to it)
_CANONICAL = np.array([0.5773, 0.5774, 0.5775])
#: a wall is a closed body crossed in and out at least this far apart (mm); a lone crossing
#: (an open surface sheet: no thickness to straddle) is a single skin
_MIN_WALL = 1e-3


@dataclass(frozen=True)
class Stack:
    """The sheets a point sits on, along its normal line (mm).

    ``bodies`` and ``gauges`` are the layers in order along ``normal``; ``gaps`` the air gaps
    between consecutive layers (``len(bodies) - 1``); ``thickness`` from the first layer's
    outer face to the last's; ``joins`` the two sheets of the faying surface the point was
    snapped to (a wall: its one body twice); ``overlap`` the stack's width across its flange
    (``inf`` when wider than the march); ``edge_distance`` to the nearest free edge (``None``
    when none within ``edge_reach``).
    """

    kind: str
    bodies: tuple[str, ...]
    gauges: tuple[float, ...]
    gaps: tuple[float, ...]
    thickness: float
    normal: tuple[float, float, float]
    joins: tuple[str, str]
    overlap: float
    edge_distance: float | None


@dataclass(frozen=True)
class SpotSnap:
    """Where one spot lands: the verdict (:data:`VERDICTS`), why, and the stack if any.

    ``position`` is the snapped spot (3,) mm (``None`` with ``"no sheet"``); ``distance`` how far
    the spot was from it (or from the nearest sheet).
    """

    index: int
    ok: bool
    verdict: str
    reason: str
    position: tuple[float, float, float] | None
    distance: float
    stack: Stack | None


@dataclass(frozen=True)
class FlangePatch:
    """A connected region of one stack (:func:`find_flanges`); lengths mm, area mm^2."""

    centre: tuple[float, float, float]
    normal: tuple[float, float, float]
    kind: str
    bodies: tuple[str, ...]
    gap: float
    thickness: float
    gauges: tuple[float, ...]
    overlap: float
    edge_distance: float | None
    length: float
    area: float


def _sheets(part_or_sheets: Any) -> Sheets:
    return part_or_sheets if isinstance(part_or_sheets, Sheets) else Sheets(part_or_sheets)


def snap_spots(
    part_or_sheets: Any, points: ArrayLike, settings: FlangeSettings | None = None
) -> tuple[SpotSnap, ...]:
    """The stack each spot sits on, snapped onto its faying surface, or why none.

    Parameters
    ----------
    part_or_sheets
        The part (module docstring) or a prepared :class:`Sheets`.
    points
        ``(n, 3)`` spots, mm.
    settings
        :class:`FlangeSettings` (default values when ``None``).

    Returns
    -------
    tuple of SpotSnap
        One per spot, in order; never raises for a spot that has no stack (its verdict says
        why: :data:`VERDICTS`).
    """
    s = settings or FlangeSettings()
    sheets = _sheets(part_or_sheets)
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(P)):
        raise InputError("spot coordinates must be finite", field="xyz")
    if len(P) == 0:
        return ()
    X, body, N = sheets.closest(P)
    dist = np.linalg.norm(X - P, axis=1)
    # the normal line through the spot's nearest sheet point, oriented as the face normal
    f = find_stacks(sheets, X, N, s)
    out: dict[int, SpotSnap] = {}
    stacks: dict[int, tuple[Stack, NDArray[np.float64]]] = {}
    for i in range(len(P)):
        if dist[i] > s.search_radius:
            why = f"no sheet within {s.search_radius:g} mm (the nearest is {dist[i]:.1f} mm away)"
            out[i] = SpotSnap(i, False, "no sheet", why, None, float(dist[i]), None)
            continue
        verdict, reason, st, pos = _verdict(sheets, f, i, X[i], N[i], s)
        if st is None:
            out[i] = SpotSnap(i, False, verdict, reason, _t3(X[i]), float(dist[i]), None)
        else:
            stacks[i] = (st, pos)
    idx = sorted(stacks)
    if idx:
        C = np.array([stacks[i][1] for i in idx])
        Nn = np.array([stacks[i][0].normal for i in idx])
        A = np.array([sheets.names.index(stacks[i][0].joins[0]) for i in idx])
        B = np.array([sheets.names.index(stacks[i][0].joins[1]) for i in idx])
        T = np.array([stacks[i][0].thickness for i in idx])
        ov, edge = march(sheets, C, Nn, A, B, T, s)
        for k, i in enumerate(idx):
            st = _with_edge(stacks[i][0], ov[k], edge[k])
            pos = stacks[i][1]
            out[i] = _judged(i, st, pos, float(np.linalg.norm(pos - P[i])), s)
    return tuple(out[i] for i in range(len(P)))


def _t3(v: ArrayLike) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=np.float64).reshape(3)
    return float(a[0]), float(a[1]), float(a[2])


def _verdict(
    sheets: Sheets, f: Found, i: int, X: NDArray, N: NDArray, s: FlangeSettings
) -> tuple[str, str, Stack | None, NDArray[np.float64]]:
    """The stack at point ``i`` before the edge march, or the verdict why there is none."""
    L, W = f.layers, sheets.reach
    if f.near[i] < 0:
        return "single skin", "the normal line meets no sheet", None, X
    a, b = int(f.first[i]), int(f.last[i])
    rng_ = range(a, b + 1)
    names = tuple(sheets.names[int(L.body[k])] for k in rng_)
    gauges = tuple(round(float(L.t_out[k] - L.t_in[k]), 4) for k in rng_)
    gaps = tuple(round(float(L.t_in[k + 1] - L.t_out[k]), 4) for k in range(a, b))
    thick = float(L.t_out[b] - L.t_in[a])
    j = int(f.iface[i])
    if j < 0:  # one sheet
        if s.walls and _MIN_WALL < thick <= s.max_wall:
            pos = X + ((L.t_in[a] + L.t_out[a]) / 2 - W) * N
            st = Stack(
                "wall", names, gauges, (), thick, _t3(N), (names[0], names[0]), math.inf, None
            )
            return "wall", "", st, pos
        what = f"one sheet ({names[0]}, {thick:.2f} mm)"
        if s.walls and thick > _MIN_WALL:
            return (
                "too thick",
                f"{what} is thicker than the {s.max_wall:g} mm a gun straddles",
                None,
                X,
            )
        return "single skin", f"{what} with no second sheet within {s.max_gap:g} mm", None, X
    if thick > s.max_stack:
        return (
            "too thick",
            f"the stack is {thick:.1f} mm thick, more than {s.max_stack:g} mm",
            None,
            X,
        )
    pos = X + ((L.t_out[j] + L.t_in[j + 1]) / 2 - W) * N
    joins = (sheets.names[int(L.body[j])], sheets.names[int(L.body[j + 1])])
    st = Stack("lap", names, gauges, gaps, thick, _t3(N), joins, math.inf, None)
    return "stack", "", st, pos


def _with_edge(st: Stack, overlap: float, edge: float) -> Stack:
    from dataclasses import replace

    return replace(
        st, overlap=float(overlap), edge_distance=None if math.isnan(edge) else float(edge)
    )


def _judged(i: int, st: Stack, pos: NDArray, dist: float, s: FlangeSettings) -> SpotSnap:
    """The spot's verdict once its stack's overlap and edge are known."""
    what = f"{' + '.join(st.bodies)} ({st.thickness:.2f} mm)"
    if st.overlap < s.min_overlap:
        reason = f"{what} overlap {st.overlap:.1f} mm wide, less than {s.min_overlap:g} mm"
        return SpotSnap(i, False, "narrow overlap", reason, _t3(pos), dist, st)
    if st.edge_distance is None:
        reason = f"{what} has no free edge within {s.edge_reach:g} mm"
        return SpotSnap(i, False, "no free edge", reason, _t3(pos), dist, st)
    joins = (
        f"is a wall of {st.joins[0]}" if st.kind == "wall" else "joins " + " and ".join(st.joins)
    )
    reason = f"{joins}: {what}, edge {st.edge_distance:.1f} mm away"
    return SpotSnap(i, True, st.kind if st.kind == "wall" else "stack", reason, _t3(pos), dist, st)


def find_flanges(
    part_or_sheets: Any, settings: FlangeSettings | None = None, *, rng: RNGLike = 0
) -> tuple[FlangePatch, ...]:
    """Every stack of the part (and every thin wall with ``settings.walls``) as a patch.

    The sheets' surfaces are sampled about ``spacing`` mm apart (``rng``: the sample points),
    the stack at each sample is found along its normal line (module docstring) and snapped to
    its faying surface; samples of one pair of sheets whose snapped points lie within twice the
    spacing of each other form a patch. A patch is reported when its stack, measured by the edge
    march from its centre (the sample nearest the patch's mean), is at least ``min_overlap``
    wide and has a free edge within ``edge_reach``.

    Returns
    -------
    tuple of FlangePatch
        Largest area first. ``gap`` and ``thickness`` are medians over the patch's samples,
        ``length`` its extent along its main axis.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    s = settings or FlangeSettings()
    sheets = _sheets(part_or_sheets)
    gen = as_generator(rng)
    m = sheets.mesh
    count = max(int(math.ceil(m.area / s.spacing**2)), 1)
    P, face = trimesh.sample.sample_surface(m, count, seed=int(gen.integers(2**31)))
    P, N = np.asarray(P, np.float64), np.asarray(m.face_normals, np.float64)[face]
    f = find_stacks(sheets, P, N, s)
    L, W = f.layers, sheets.reach
    thick = f.thickness()
    j = f.iface
    lap = (j >= 0) & (thick <= s.max_stack)
    A = np.where(lap, L.body[np.maximum(j, 0)], -1)
    B = np.where(lap, L.body[np.maximum(j, 0) + 1], -1)
    t_snap = np.where(lap, (L.t_out[np.maximum(j, 0)] + L.t_in[np.maximum(j, 0) + 1]) / 2, np.nan)
    if s.walls:
        wall = ~lap & (f.near >= 0) & (f.iface < 0) & (thick > _MIN_WALL) & (thick <= s.max_wall)
        k = np.maximum(f.first, 0)
        A = np.where(wall, L.body[k], A)
        B = np.where(wall, L.body[k], B)
        t_snap = np.where(wall, (L.t_in[k] + L.t_out[k]) / 2, t_snap)
        lap |= wall
    idx = np.flatnonzero(lap)
    if len(idx) == 0:
        return ()
    lo, hi = np.minimum(A[idx], B[idx]), np.maximum(A[idx], B[idx])
    # normals oriented from the lower sheet index to the higher; a wall's by a fixed direction
    sgn = np.where(A[idx] < B[idx], 1.0, -1.0)
    wall_sgn = np.where(N[idx] @ _CANONICAL >= 0, 1.0, -1.0)
    sgn = np.where(A[idx] == B[idx], wall_sgn, sgn)[:, None]
    X = P[idx] + (t_snap[idx] - W)[:, None] * N[idx]
    Nn = N[idx] * sgn
    pairs = cKDTree(X).query_pairs(2 * s.spacing, output_type="ndarray")
    same = (lo[pairs[:, 0]] == lo[pairs[:, 1]]) & (hi[pairs[:, 0]] == hi[pairs[:, 1]])
    same &= np.einsum("ij,ij->i", Nn[pairs[:, 0]], Nn[pairs[:, 1]]) > 0.5
    pairs = pairs[same]
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(idx),) * 2)
    _, label = connected_components(g, directed=False)
    groups = [np.flatnonzero(label == c) for c in np.unique(label)]
    groups = [g_ for g_ in groups if len(g_) >= 3]
    return _patches(sheets, f, idx, X, Nn, lo, hi, groups, s)


def _patches(
    sheets: Sheets, f: Found, idx: NDArray, X: NDArray, Nn: NDArray, lo: NDArray, hi: NDArray,
    groups: list[NDArray], s: FlangeSettings,
) -> tuple[FlangePatch, ...]:  # fmt: skip
    """The patches of :func:`find_flanges`: per group of samples, its stack and edge march."""
    L = f.layers
    centre = []
    for g in groups:
        c = X[g].mean(axis=0)
        centre.append(g[int(np.argmin(np.linalg.norm(X[g] - c, axis=1)))])
    c_idx = np.array(centre)
    thick = f.thickness()[idx]
    ov, edge = march(sheets, X[c_idx], Nn[c_idx], lo[c_idx], hi[c_idx], thick[c_idx], s)
    out = []
    for k, g in enumerate(groups):
        if ov[k] < s.min_overlap or math.isnan(edge[k]):
            continue
        j = f.iface[idx[g]]
        gap = float(np.median(L.t_in[j + 1] - L.t_out[j])) if np.all(j >= 0) else 0.0
        a, b = int(f.first[idx[c_idx[k]]]), int(f.last[idx[c_idx[k]]])
        gauges = tuple(round(float(L.t_out[q] - L.t_in[q]), 4) for q in range(a, b + 1))
        bodies = tuple(sheets.names[int(L.body[q])] for q in range(a, b + 1))
        Y = X[g] - X[g].mean(axis=0)
        axis = np.linalg.svd(Y, full_matrices=False)[2][0] if len(g) > 1 else np.zeros(3)
        proj = Y @ axis
        out.append(
            FlangePatch(
                centre=_t3(X[c_idx[k]]),
                normal=_t3(Nn[c_idx[k]]),
                kind="wall" if lo[c_idx[k]] == hi[c_idx[k]] else "lap",
                bodies=bodies,
                gap=gap,
                thickness=float(np.median(thick[g])),
                gauges=gauges,
                overlap=float(ov[k]),
                edge_distance=float(edge[k]),
                length=float(proj.max() - proj.min()),
                area=float(len(g) * s.spacing**2),
            )
        )
    out.sort(key=lambda p: -p.area)
    return tuple(out)
