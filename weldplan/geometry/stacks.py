"""Sheet stacks along normal lines: the ray casts under :mod:`weldplan.geometry.flanges`.

Through a point, the whole normal line is cast against every sheet at once
(open3d ``RaycastingScene.list_intersections``: C++, all rays in one call). The hits of one
sheet pair into layers (entry, exit; a lone hit is a zero-thickness surface sheet), consecutive
layers whose faying faces are parallel and at most ``max_gap`` apart form runs, and the run
nearest the point is its stack. The edge march (:func:`march`) probes the same way at points
around a stack's centre. Everything is arrays over all rays; the only Python loops are over
sheets. The settings are :class:`FlangeSettings`; the user API is in
:mod:`weldplan.geometry.flanges`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.errors import ConfigError, InputError

#: hits of one ray on one sheet closer than this (mm) are one hit (a ray through a shared edge)
_SAME_HIT_MM = 1e-4


@dataclass(frozen=True)
class FlangeSettings:
    """What counts as a stack a gun can close on (mm, degrees); :mod:`weldplan.geometry.flanges`.

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
    edge_reach, edge_step, directions
        The edge march: how far, how fine up to 40 mm, in how many directions (even).
    walls, max_wall
        Slab models: a single body at most ``max_wall`` thick counts as a ``"wall"``.
    spacing
        :func:`~weldplan.geometry.flanges.find_flanges` samples the sheets' surfaces about
        this far apart.
    """

    max_gap: float = 4.0
    parallel_deg: float = 15.0
    min_overlap: float = 14.0
    max_stack: float = 40.0
    search_radius: float = 20.0
    edge_reach: float = 250.0
    edge_step: float = 0.5
    directions: int = 16
    walls: bool = False
    max_wall: float = 36.0
    spacing: float = 5.0

    def __post_init__(self) -> None:
        for name in (
            "max_gap", "parallel_deg", "min_overlap", "max_stack", "search_radius",
            "edge_reach", "edge_step", "max_wall", "spacing",
        ):  # fmt: skip
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigError(f"flange setting {name} must be a positive number, got {v!r}")
        if self.directions < 4 or self.directions % 2:
            raise ConfigError(f"directions must be an even number >= 4, got {self.directions}")


class Sheets:
    """The sheets of a part, prepared for ray casts (one open3d scene; each face knows its sheet).

    Parameters
    ----------
    part_or_sheets
        A mesh (connected components are the sheets), a Scene, a ``{name: mesh}`` mapping or a
        list of meshes (mm).

    Attributes
    ----------
    names
        The sheets' names; ``body0, body1, ...`` for a mesh or a list.
    mesh
        All sheets in one mesh, and ``face_sheet (faces,)`` the sheet of each face.
    reach
        mm: every normal line starts this far behind its point, outside the part's bounding
        box, so that every sheet it crosses is crossed whole.
    """

    def __init__(self, part_or_sheets: Any) -> None:
        import open3d as o3d

        names, mesh, face_sheet = _split(part_or_sheets)
        self.names: tuple[str, ...] = tuple(names)
        self.mesh = mesh
        self.face_sheet = face_sheet
        self._normals = np.asarray(mesh.face_normals, np.float64)
        self.reach = float(np.linalg.norm(mesh.extents)) + 10.0
        self.scene = o3d.t.geometry.RaycastingScene()
        self.scene.add_triangles(
            np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32)
        )

    def closest(self, points: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        """Nearest sheet points ``(n, 3)``, their sheet ``(n,)`` and face normal ``(n, 3)``."""
        q = self.scene.compute_closest_points(np.asarray(points, np.float32))
        face = q["primitive_ids"].numpy().astype(np.int64)
        X = q["points"].numpy().astype(np.float64)
        return X, self.face_sheet[face], self._normals[face]

    def layers(self, points: NDArray, dirs: NDArray) -> _Layers:
        """The layers crossed by the lines through ``points (n, 3)`` along unit ``dirs (n, 3)``,
        at depths ``t`` from ``points - reach * dirs`` (the point itself at ``t = reach``)."""
        rays = np.hstack([points - self.reach * dirs, dirs]).astype(np.float32)
        lx = {k: v.numpy() for k, v in self.scene.list_intersections(rays).items()}
        ray = lx["ray_ids"].astype(np.int64)
        face = lx["primitive_ids"].astype(np.int64)
        t = lx["t_hit"].astype(np.float64)
        cos = np.einsum("ij,ij->i", self._normals[face], dirs[ray])
        return _pair_hits(ray, self.face_sheet[face], t, cos)


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


def _split(part_or_sheets: Any) -> tuple[list[str], trimesh.Trimesh, NDArray[np.int64]]:
    """Names of the sheets, all of them in one mesh, and the sheet of each of its faces."""
    obj = part_or_sheets
    if isinstance(obj, trimesh.Scene):
        obj = {name: g for name, g in obj.geometry.items() if isinstance(g, trimesh.Trimesh)}
    if isinstance(obj, trimesh.Trimesh):
        if len(obj.faces) == 0:
            raise InputError("the part has no triangles", field="part")
        labels = trimesh.graph.connected_component_labels(obj.face_adjacency, len(obj.faces))
        _, labels = np.unique(labels, return_inverse=True)
        return [f"body{k}" for k in range(labels.max() + 1)], obj, labels.astype(np.int64)
    if isinstance(obj, Mapping):
        names, meshes = [str(k) for k in obj], list(obj.values())
    elif isinstance(obj, Sequence):
        meshes, names = list(obj), [f"body{k}" for k in range(len(obj))]
    else:
        raise TypeError(
            "give a trimesh.Trimesh, a Scene, a {name: mesh} mapping or a list of meshes"
        )
    if not meshes or any(not isinstance(m, trimesh.Trimesh) or len(m.faces) == 0 for m in meshes):
        raise InputError("the part has no sheet with triangles", field="part")
    labels = np.repeat(np.arange(len(meshes)), [len(m.faces) for m in meshes])
    return names, trimesh.util.concatenate(meshes), labels


@dataclass(frozen=True)
class Found:
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


def find_stacks(sheets: Sheets, P: NDArray, N: NDArray, s: FlangeSettings) -> Found:
    """Cast the normal line through every point ``P (n, 3)`` along ``N (n, 3)``; the stack of
    each (module docstring): the run of the layer nearest the point and its faying surface
    nearest the point."""
    n, W = len(P), sheets.reach
    L = sheets.layers(P, N)
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
    return Found(L, run, near, first, last, iface)


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
    W = sheets.reach
    Q = C[:, None, None] + radii[..., None] * D[:, :, None]  # (m, K, r, 3)
    NN = np.broadcast_to(N[:, None, None], Q.shape).reshape(-1, 3)
    Q = Q.reshape(-1, 3)
    owner = np.repeat(np.arange(m), K * r)
    L = sheets.layers(Q, NN)
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
    w_ok &= (L.t_out - L.t_in <= thick[o] + s.max_gap) & (L.t_out > L.t_in)
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


def march(
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
