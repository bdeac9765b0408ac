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
Through a point, the **normal line** (the normal of the nearest sheet face, ``window`` mm each
way) is cast against every sheet at once (``RaycastingScene.list_intersections``). The hits of
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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import ConfigError, InputError
from weldplan.random import RNGLike, as_generator

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
#: hits of one ray on one sheet closer than this (mm) are one hit (a ray through a shared edge)
_SAME_HIT_MM = 1e-4


@dataclass(frozen=True)
class FlangeSettings:
    """What counts as a stack a gun can close on (mm, degrees); module docstring.

    Parameters
    ----------
    max_gap
        Largest air gap between two sheets face to face (issue 29: 0.5-4 mm apart).
    parallel_deg
        Faces of a stack lie within this angle of perpendicular to the normal line.
    min_overlap
        Narrowest overlap (width of the stack across its flange) that counts; issue 29's
        "at least ~15 mm", less the march's resolution.
    max_stack
        Thickest stack that counts (the shared C-gun opens 46.5 mm; less room for clearance).
    search_radius
        A spot farther than this from every sheet is ``"no sheet"``.
    window
        Half-length of the normal line cast through a point.
    edge_reach, edge_step, directions
        The edge march: how far, how fine up to 40 mm, in how many directions (even).
    walls, max_wall
        Slab models: a single body at most ``max_wall`` thick counts as a ``"wall"``.
    spacing
        :func:`find_flanges` samples the sheets' surfaces about this far apart.
    """

    max_gap: float = 4.0
    parallel_deg: float = 15.0
    min_overlap: float = 14.0
    max_stack: float = 40.0
    search_radius: float = 20.0
    window: float = 60.0
    edge_reach: float = 250.0
    edge_step: float = 0.5
    directions: int = 16
    walls: bool = False
    max_wall: float = 36.0
    spacing: float = 5.0

    def __post_init__(self) -> None:
        for name in (
            "max_gap", "parallel_deg", "min_overlap", "max_stack", "search_radius", "window",
            "edge_reach", "edge_step", "max_wall", "spacing",
        ):  # fmt: skip
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigError(f"flange setting {name} must be a positive number, got {v!r}")
        if self.directions < 4 or self.directions % 2:
            raise ConfigError(f"directions must be an even number >= 4, got {self.directions}")


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


class Sheets:
    """The sheets of a part, prepared for ray casts (an open3d scene, one geometry per sheet).

    Parameters
    ----------
    part_or_sheets
        A mesh (connected components are the sheets), a Scene, a ``{name: mesh}`` mapping or a
        list of meshes (mm).
    """

    def __init__(self, part_or_sheets: Any) -> None:
        import open3d as o3d

        names, meshes = _split(part_or_sheets)
        self.names: tuple[str, ...] = tuple(names)
        self.scene = o3d.t.geometry.RaycastingScene()
        self._normals = []
        for m in meshes:
            gid = self.scene.add_triangles(
                np.asarray(m.vertices, np.float32), np.asarray(m.faces, np.uint32)
            )
            if gid != len(self._normals):
                raise RuntimeError("open3d geometry ids out of order")
            self._normals.append(np.asarray(m.face_normals, np.float64))
        self.meshes: tuple[trimesh.Trimesh, ...] = tuple(meshes)

    def closest(self, points: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        """Nearest sheet points ``(n, 3)``, their sheet ``(n,)`` and face normal ``(n, 3)``."""
        q = self.scene.compute_closest_points(np.asarray(points, np.float32))
        body = q["geometry_ids"].numpy().astype(np.int64)
        face = q["primitive_ids"].numpy().astype(np.int64)
        normal = np.zeros((len(body), 3))
        for b in np.unique(body):
            normal[body == b] = self._normals[b][face[body == b]]
        return q["points"].numpy().astype(np.float64), body, normal

    def layers(self, origins: NDArray, dirs: NDArray, length: float) -> _Layers:
        """The layers crossed by rays ``origins + t dirs``, ``0 <= t <= length`` (unit dirs)."""
        rays = np.hstack([origins, dirs]).astype(np.float32)
        lx = {k: v.numpy() for k, v in self.scene.list_intersections(rays).items()}
        ray = lx["ray_ids"].astype(np.int64)
        body = lx["geometry_ids"].astype(np.int64)
        t = lx["t_hit"].astype(np.float64)
        face = lx["primitive_ids"].astype(np.int64)
        keep = t <= length
        ray, body, t, face = ray[keep], body[keep], t[keep], face[keep]
        n = np.zeros((len(t), 3))
        for b in np.unique(body):
            sel = body == b
            n[sel] = self._normals[b][face[sel]]
        cos = np.einsum("ij,ij->i", n, dirs[ray])
        return _pair_hits(ray, body, t, cos)


@dataclass(frozen=True)
class _Layers:
    """Layers of many rays, sorted by ray then depth: flat arrays ``(k,)``."""

    ray: NDArray[np.int64]
    body: NDArray[np.int64]
    t_in: NDArray[np.float64]
    t_out: NDArray[np.float64]
    cos_in: NDArray[np.float64]  # |cos| of the entry and exit faces' normals to the ray
    cos_out: NDArray[np.float64]

    def runs(self, max_gap: float, min_cos: float) -> NDArray[np.int64]:
        """Run id ``(k,)`` of each layer: consecutive parallel layers at most ``max_gap`` apart."""
        k = len(self.ray)
        if k == 0:
            return np.zeros(0, np.int64)
        same = self.ray[1:] == self.ray[:-1]
        close = self.t_in[1:] - self.t_out[:-1] <= max_gap
        flat = (self.cos_in[1:] >= min_cos) & (self.cos_out[:-1] >= min_cos)  # the faying faces
        new = np.concatenate([[True], ~(same & close & flat)])
        return np.cumsum(new) - 1

    def nearest(self, n_rays: int, t_ref: float) -> NDArray[np.int64]:
        """Per ray, the index of the layer nearest depth ``t_ref`` (-1 where the ray has none)."""
        d = np.maximum.reduce([self.t_in - t_ref, t_ref - self.t_out, np.zeros(len(self.ray))])
        order = np.lexsort((d, self.ray))
        out = np.full(n_rays, -1, np.int64)
        first = np.concatenate([[True], self.ray[order][1:] != self.ray[order][:-1]])
        out[self.ray[order][first]] = order[first]
        return out

    def dist(self, idx: NDArray[np.int64], t_ref: float) -> NDArray[np.float64]:
        return np.maximum.reduce(
            [self.t_in[idx] - t_ref, t_ref - self.t_out[idx], np.zeros(len(idx))]
        )


def _pair_hits(ray: NDArray, body: NDArray, t: NDArray, cos: NDArray) -> _Layers:
    """Hits sorted, duplicates merged, paired into layers (entry then exit of one sheet)."""
    order = np.lexsort((t, body, ray))
    ray, body, t, cos = ray[order], body[order], t[order], cos[order]
    dup = np.concatenate(
        [[False], (ray[1:] == ray[:-1]) & (body[1:] == body[:-1]) & (t[1:] - t[:-1] < _SAME_HIT_MM)
         & (np.sign(cos[1:]) == np.sign(cos[:-1]))]
    )  # fmt: skip
    ray, body, t, cos = ray[~dup], body[~dup], t[~dup], cos[~dup]
    enter = cos < 0
    start = np.zeros(len(t), bool)
    if len(t) > 1:
        start[:-1] = (ray[1:] == ray[:-1]) & (body[1:] == body[:-1]) & enter[:-1] & ~enter[1:]
    paired = start | np.concatenate([[False], start[:-1]])
    s = np.flatnonzero(start)
    lone = np.flatnonzero(~paired)
    L_ray = np.concatenate([ray[s], ray[lone]])
    L_body = np.concatenate([body[s], body[lone]])
    L_in = np.concatenate([t[s], t[lone]])
    L_out = np.concatenate([t[s + 1], t[lone]])
    c_in = np.concatenate([abs(cos[s]), abs(cos[lone])])
    c_out = np.concatenate([abs(cos[s + 1]), abs(cos[lone])])
    o = np.lexsort((L_in, L_ray))
    return _Layers(L_ray[o], L_body[o], L_in[o], L_out[o], c_in[o], c_out[o])


def _split(part_or_sheets: Any) -> tuple[list[str], list[trimesh.Trimesh]]:
    """Names and meshes of the sheets (class docstring of :class:`Sheets`)."""
    obj = part_or_sheets
    if isinstance(obj, trimesh.Scene):
        obj = {name: g for name, g in obj.geometry.items() if isinstance(g, trimesh.Trimesh)}
    if isinstance(obj, Mapping):
        names, meshes = [str(k) for k in obj], list(obj.values())
    elif isinstance(obj, trimesh.Trimesh):
        labels = trimesh.graph.connected_component_labels(obj.face_adjacency, len(obj.faces))
        meshes = [
            obj.submesh([np.flatnonzero(labels == c)], append=True) for c in np.unique(labels)
        ]
        names = [f"body{k}" for k in range(len(meshes))]
    elif isinstance(obj, Sequence):
        meshes, names = list(obj), [f"body{k}" for k in range(len(obj))]
    else:
        raise TypeError(
            "give a trimesh.Trimesh, a Scene, a {name: mesh} mapping or a list of meshes"
        )
    if not meshes or any(not isinstance(m, trimesh.Trimesh) or len(m.faces) == 0 for m in meshes):
        raise InputError("the part has no sheet with triangles", field="part")
    return names, meshes


@dataclass(frozen=True)
class _Found:
    """The stack at each of ``n`` points (internal, vectorised): arrays ``(n,)``."""

    layers: _Layers
    run: NDArray[np.int64]  # run id of every layer
    near: NDArray[np.int64]  # the layer nearest each point (-1: none)
    first: NDArray[np.int64]  # first and last layer of that layer's run
    last: NDArray[np.int64]
    iface: NDArray[np.int64]  # the layer before the faying surface nearest the point (-1: none)

    def thickness(self) -> NDArray[np.float64]:
        ok = self.near >= 0
        out = np.full(len(self.near), np.nan)
        out[ok] = self.layers.t_out[self.last[ok]] - self.layers.t_in[self.first[ok]]
        return out


def _find(sheets: Sheets, P: NDArray, N: NDArray, s: FlangeSettings) -> _Found:
    """Cast the normal line through every point ``P (n, 3)`` along ``N (n, 3)``; the stack of
    each (module docstring): the run of the layer nearest the point and its faying surface
    nearest the point."""
    n, W = len(P), s.window
    L = sheets.layers(P - W * N, N, 2 * W)
    run = L.runs(s.max_gap, math.cos(math.radians(s.parallel_deg)))
    near = L.nearest(n, W)
    has = near >= 0
    far = np.zeros(n, bool)
    far[has] = L.dist(near[has], W) > s.max_gap + s.search_radius
    near[far] = -1
    k = len(L.ray)
    starts = (
        np.flatnonzero(np.concatenate([[True], run[1:] != run[:-1]])) if k else np.zeros(0, int)
    )
    ends = np.concatenate([starts[1:] - 1, [k - 1]]) if k else np.zeros(0, int)
    first = np.full(n, -1, np.int64)
    last = np.full(n, -1, np.int64)
    ok = near >= 0
    first[ok] = starts[run[near[ok]]]
    last[ok] = ends[run[near[ok]]]
    # faying surfaces: consecutive layers of one run and two sheets; the one nearest each point
    j = (
        np.flatnonzero((run[1:] == run[:-1]) & (L.body[1:] != L.body[:-1]))
        if k > 1
        else np.zeros(0, int)
    )
    iface = np.full(n, -1, np.int64)
    if len(j):
        r = L.ray[j]
        mine = ok[r] & (run[j] == run[np.maximum(near[r], 0)])
        j, r = j[mine], r[mine]
        d = np.abs((L.t_out[j] + L.t_in[j + 1]) / 2 - W)
        o = np.lexsort((d, r))
        head = np.concatenate([[True], r[o][1:] != r[o][:-1]]) if len(o) else np.zeros(0, bool)
        iface[r[o][head]] = j[o][head]
    return _Found(L, run, near, first, last, iface)


def _plane_axes(N: NDArray) -> tuple[NDArray, NDArray]:
    """Two unit vectors ``(n, 3)`` spanning the plane perpendicular to each ``N (n, 3)``."""
    a = np.where(np.abs(N[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    e1 = np.cross(N, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(N, e1)


def _probe(
    sheets: Sheets, C: NDArray, N: NDArray, D: NDArray, radii: NDArray, A: NDArray, B: NDArray,
    thick: NDArray, s: FlangeSettings,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:  # fmt: skip
    """At the points ``C + r D`` (``D (m, K, 3)`` unit directions in each stack's plane,
    ``radii (m, K, r)`` mm): whether the stack of ``C[i]`` (sheets ``A[i]``, ``B[i]`` face to
    face; a wall when equal) goes on, and whether any sheet lies within its thickness plus
    ``max_gap`` of its plane. Both ``(m, K, r) bool``."""
    m, K, r = radii.shape
    W = s.window
    Q = C[:, None, None] + radii[..., None] * D[:, :, None]  # (m, K, r, 3)
    NN = np.broadcast_to(N[:, None, None], Q.shape).reshape(-1, 3)
    Q = Q.reshape(-1, 3)
    owner = np.repeat(np.arange(m), K * r)
    L = sheets.layers(Q - W * NN, NN, 2 * W)
    o = owner[L.ray]
    reach = thick[o] + s.max_gap
    mid_d = np.maximum.reduce([L.t_in - W, W - L.t_out, np.zeros(len(L.ray))])
    material = np.zeros(len(Q), bool)
    material[L.ray[mid_d <= reach]] = True
    cont = np.zeros(len(Q), bool)
    min_cos = math.cos(math.radians(s.parallel_deg))
    wall = A[o] == B[o]
    w_ok = wall & (L.body == A[o]) & (mid_d <= reach)
    w_ok &= (L.cos_in >= min_cos) & (L.cos_out >= min_cos)
    w_ok &= L.t_out - L.t_in <= thick[o] + s.max_gap
    cont[L.ray[w_ok]] = True
    if len(L.ray) > 1:
        j = np.arange(len(L.ray) - 1)
        oj = o[j]
        pair = (L.ray[j + 1] == L.ray[j]) & ~wall[j]
        pair &= ((L.body[j] == A[oj]) & (L.body[j + 1] == B[oj])) | (
            (L.body[j] == B[oj]) & (L.body[j + 1] == A[oj])
        )
        pair &= (L.t_in[j + 1] - L.t_out[j] <= s.max_gap) & (L.cos_out[j] >= min_cos)
        pair &= (L.cos_in[j + 1] >= min_cos) & (
            np.abs((L.t_out[j] + L.t_in[j + 1]) / 2 - W) <= reach[j]
        )
        cont[L.ray[j[pair]]] = True
    return cont.reshape(m, K, r), material.reshape(m, K, r)


def _first_break(cont: NDArray[np.bool_]) -> NDArray[np.int64]:
    """Index of the first ``False`` along the last axis (its length where there is none)."""
    return np.where((~cont).any(axis=-1), (~cont).argmax(axis=-1), cont.shape[-1])


def _march(
    sheets: Sheets, C: NDArray, N: NDArray, A: NDArray, B: NDArray, thick: NDArray,
    s: FlangeSettings,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """Overlap width and free-edge distance ``(m,)`` of the stacks at ``C (m, 3)`` joining
    sheets ``A, B (m,)`` (``A == B``: a wall), by marching in the plane (module docstring):
    every ``edge_step`` to 40 mm, every 5 mm beyond, and the 5 mm steps where the stack broke
    refined to ``edge_step``. ``inf`` overlap: wider than the march; ``nan`` edge: no free
    edge within reach."""
    m, K = len(C), s.directions
    R = np.concatenate(
        [
            np.arange(s.edge_step, 40.0 + 1e-9, s.edge_step),
            np.arange(45.0, s.edge_reach + 1e-9, 5.0),
        ]
    )
    ang = 2 * np.pi * np.arange(K) / K
    e1, e2 = _plane_axes(N)
    D = np.cos(ang)[None, :, None] * e1[:, None] + np.sin(ang)[None, :, None] * e2[:, None]
    cont, material = _probe(sheets, C, N, D, np.broadcast_to(R, (m, K, len(R))), A, B, thick, s)
    i = _first_break(cont)  # (m, K)
    Rpad = np.concatenate([[0.0], R, [np.inf]])
    lo, hi = Rpad[i], Rpad[i + 1]  # the last radius the stack held and the first it broke at
    at = np.minimum(i, len(R) - 1)
    mat = np.take_along_axis(material, at[..., None], axis=2)[..., 0]
    coarse = (i < len(R)) & (hi - lo > s.edge_step + 1e-9)
    if coarse.any():
        steps = np.arange(1, int(round(5.0 / s.edge_step)) + 1) * s.edge_step
        fine = np.where(coarse[..., None], lo[..., None] + steps, 0.0)  # 0: not probed again
        c2, m2 = _probe(sheets, C, N, D, fine, A, B, thick, s)
        k2 = np.minimum(_first_break(c2), len(steps) - 1)
        f_hi = np.take_along_axis(fine, k2[..., None], axis=2)[..., 0]
        f_mat = np.take_along_axis(m2, k2[..., None], axis=2)[..., 0]
        lo = np.where(coarse, f_hi - s.edge_step, lo)
        hi = np.where(coarse, f_hi, hi)
        mat = np.where(coarse, f_mat, mat)
    ext = np.where(i < len(R), (lo + hi) / 2, np.inf)
    free = (i < len(R)) & ~mat
    overlap = np.min(ext[:, : K // 2] + ext[:, K // 2 :], axis=1)
    edge = np.where(free, ext, np.inf).min(axis=1)
    return overlap, np.where(np.isfinite(edge), edge, np.nan)


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
    f = _find(sheets, X, N, s)
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
        ov, edge = _march(sheets, C, Nn, A, B, T, s)
        for k, i in enumerate(idx):
            st = _with_edge(stacks[i][0], ov[k], edge[k])
            pos = stacks[i][1]
            out[i] = _judged(i, st, pos, float(np.linalg.norm(pos - P[i])), s)
    return tuple(out[i] for i in range(len(P)))


def _t3(v: ArrayLike) -> tuple[float, float, float]:
    a = np.asarray(v, dtype=np.float64).reshape(3)
    return float(a[0]), float(a[1]), float(a[2])


def _verdict(
    sheets: Sheets, f: _Found, i: int, X: NDArray, N: NDArray, s: FlangeSettings
) -> tuple[str, str, Stack | None, NDArray[np.float64]]:
    """The stack at point ``i`` before the edge march, or the verdict why there is none."""
    L, W = f.layers, s.window
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
        if s.walls and thick <= s.max_wall:
            pos = X + ((L.t_in[a] + L.t_out[a]) / 2 - W) * N
            st = Stack(
                "wall", names, gauges, (), thick, _t3(N), (names[0], names[0]), math.inf, None
            )
            return "wall", "", st, pos
        what = f"one sheet ({names[0]}, {thick:.2f} mm)"
        if s.walls:
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
    reason = f"joins {st.joins[0]} and {st.joins[1]}: {what}, edge {st.edge_distance:.1f} mm away"
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
    pts, nrm = [], []
    for m in sheets.meshes:
        count = max(int(math.ceil(m.area / s.spacing**2)), 1)
        P, face = trimesh.sample.sample_surface(m, count, seed=int(gen.integers(2**31)))
        pts.append(np.asarray(P))
        nrm.append(np.asarray(m.face_normals)[face])
    P, N = np.concatenate(pts), np.concatenate(nrm)
    f = _find(sheets, P, N, s)
    L, W = f.layers, s.window
    thick = f.thickness()
    j = f.iface
    lap = (j >= 0) & (thick <= s.max_stack)
    A = np.where(lap, L.body[np.maximum(j, 0)], -1)
    B = np.where(lap, L.body[np.maximum(j, 0) + 1], -1)
    t_snap = np.where(lap, (L.t_out[np.maximum(j, 0)] + L.t_in[np.maximum(j, 0) + 1]) / 2, np.nan)
    if s.walls:
        wall = ~lap & (f.near >= 0) & (f.iface < 0) & (thick <= s.max_wall)
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
    sheets: Sheets, f: _Found, idx: NDArray, X: NDArray, Nn: NDArray, lo: NDArray, hi: NDArray,
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
    ov, edge = _march(sheets, X[c_idx], Nn[c_idx], lo[c_idx], hi[c_idx], thick[c_idx], s)
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
