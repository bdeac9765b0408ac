"""The clearance of many weld-pose candidates at once: sphere bounds first, FCL on a few pieces.

Why. The pose search (:mod:`weldplan.tool.poses.choice`) measures, lazily, whether a candidate
that does not collide keeps the clearance from the part. One python-fcl ``distance`` of the
whole shared gun (26,648 triangles outside its contact zone) costs 1.5-4 ms, and the demo's
least-rotation choice asked about 1,700 of them (0.3 s a weld). Almost all of the gun is far
from the part at any pose; only a few of its pieces decide.

The pieces. The tool outside its zone (the very triangles of the search's FCL model,
:meth:`~weldplan.tool.model.Tool.fcl_model`), its long triangles split until no edge exceeds
:data:`PIECE_EDGE_MM` (midpoint subdivision: the same surface), is cut into **pieces**: the
triangles whose centroids share a cell of :data:`PIECE_LEVELS[0]`. Each piece has a bounding
sphere (centre ``c``, radius ``r``, holding its triangles: a ball is convex) and its own
python-fcl BVH, built once per tool and zone.

The classification of candidates ``(m, 3, 3)`` at a spot ``p`` (:meth:`PoseBound.classify`):

1. a **lower bound** of each piece's distance to the part, ``d(R c + p) - r`` with ``d`` the
   distance to the part's bounding box or, where that does not decide, open3d's exact point
   distance less its round-off (:class:`~weldplan.geometry.distance.SurfaceDistance`),
   vectorised over all candidates and pieces, coarse spheres first (a sphere that clears is not
   opened). A candidate whose every piece clears the clearance is **free**: no FCL query at all.
   (The part's distance table, :class:`~weldplan.geometry.distbound.DistanceBound`, is not
   used: the gun reaches 0.7 m, and filling the table where its spheres roam cost more than
   the exact distances);
2. the other candidates ask FCL's ``distance`` of the undecided pieces only, least bound first.
   A piece closer than the clearance proves the candidate **short** (the piece is part of the
   tool, so the tool is at least that close); when every undecided piece keeps the clearance,
   the candidate is free (the cleared pieces keep it by step 1).

So the answer (free or short) is FCL's answer on the same surface, never an approximation: the
bound only decides which pieces FCL need not look at. The value returned is a bound, not the
distance; the search measures the whole tool
where it needs the distance itself (a weld's closest miss). Every chosen pose is still re-checked
by :class:`~weldplan.tool.verify.PoseChecker` (fresh FCL models of the whole tool and
part), which shares none of this.
"""

from __future__ import annotations

from dataclasses import dataclass

import fcl
import numpy as np
import trimesh
from numpy.typing import NDArray

from weldplan.geometry.distance import SurfaceDistance
from weldplan.tool.model.tool import Tool, bvh

#: mm: the tool's triangles are split until no edge is longer (a long sliver's sphere would
#: reach far beyond it; on the shared gun 26,648 triangles become 37,786 in 653 pieces, built in
#: 0.4 s; 20 mm gave 71,600 and more FCL queries of pieces, 1,000 mm (no split) three times as many)
PIECE_EDGE_MM = 40.0
#: mm: the cells of the tree, finest first: a piece is the triangles whose centroids share a
#: cell of the first; each coarser sphere holds the finer spheres whose centres share its cell
PIECE_LEVELS = (30.0, 90.0, 270.0)


@dataclass(frozen=True)
class ToolPieces:
    """The tool outside its zone cut into pieces, under a tree of spheres (module docstring).

    Attributes
    ----------
    centres, radii
        Per level, coarsest first, the pieces last: ``(s_l, 3)`` mm in the TCP frame and
        ``(s_l,)`` mm; each sphere holds the spheres of its children (and a piece's sphere its
        triangles).
    children
        Per level but the last: ``(starts (s_l + 1,), index (s_{l+1},))``, the next level's
        spheres under each sphere (CSR).
    objects
        One python-fcl object per piece (a BVH, moved by ``setTransform``).
    """

    centres: tuple[NDArray[np.float64], ...]
    radii: tuple[NDArray[np.float64], ...]
    children: tuple[tuple[NDArray[np.int64], NDArray[np.int64]], ...]
    objects: tuple[fcl.CollisionObject, ...]

    @staticmethod
    def _key(tool: Tool, radius: float) -> tuple:
        return ("pose_pieces", float(radius), tool.tip_cone, PIECE_EDGE_MM, PIECE_LEVELS)

    @classmethod
    def cached(cls, tool: Tool, radius: float) -> bool:
        """Whether :meth:`of` has built the pieces of ``tool`` for ``radius`` already."""
        return cls._key(tool, radius) in tool._cache

    @classmethod
    def of(cls, tool: Tool, radius: float) -> ToolPieces:
        """The pieces of ``tool`` outside its zone of ``radius`` mm (cached on the tool)."""
        key = cls._key(tool, radius)
        if key not in tool._cache:
            v, f = tool.outside_zone(radius)
            tool._cache[key] = cls.build(v, f)
        return tool._cache[key]

    @classmethod
    def build(cls, vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> ToolPieces:
        """Pieces of a mesh ``(n, 3)`` mm, ``(t, 3)`` and their tree (module docstring)."""
        v, f = trimesh.remesh.subdivide_to_size(
            np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int64),
            max_edge=PIECE_EDGE_MM, max_iter=30,
        )  # fmt: skip
        v, f = np.asarray(v, dtype=np.float64), np.asarray(f, dtype=np.int64)
        tri = v[f]
        group, starts, order = _cells(tri.mean(axis=1), PIECE_LEVELS[0])
        centres, radii, objects = [], [], []
        for g in range(len(starts) - 1):
            mine = order[starts[g] : starts[g + 1]]
            pts = tri[mine].reshape(-1, 3)
            c = (pts.min(axis=0) + pts.max(axis=0)) / 2
            centres.append(c)
            radii.append(float(np.linalg.norm(pts - c, axis=1).max()) * (1 + 1e-9) + 1e-9)
            objects.append(fcl.CollisionObject(bvh(v, f[mine]), fcl.Transform()))
        C, R = [np.array(centres)], [np.array(radii)]
        kids = []
        for cell in PIECE_LEVELS[1:]:
            c, r = C[-1], R[-1]
            group, starts, order = _cells(c, cell)
            lo = np.full((len(starts) - 1, 3), np.inf)
            hi = np.full((len(starts) - 1, 3), -np.inf)
            np.minimum.at(lo, group, c - r[:, None])
            np.maximum.at(hi, group, c + r[:, None])
            cc = (lo + hi) / 2
            rr = np.zeros(len(cc))
            np.maximum.at(rr, group, np.linalg.norm(c - cc[group], axis=1) + r)
            kids.append((starts.astype(np.int64), order.astype(np.int64)))
            C.append(cc)
            R.append(rr * (1 + 1e-9) + 1e-9)
        return cls(tuple(C[::-1]), tuple(R[::-1]), tuple(kids[::-1]), tuple(objects))

    def open(self, level: int, which: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray]:
        """The children of spheres ``which`` of ``level``: ``(child indices (k,), position in
        which (k,))``."""
        starts, index = self.children[level]
        n = starts[which + 1] - starts[which]
        owner = np.repeat(np.arange(len(which)), n)
        offset = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        return index[np.repeat(starts[which], n) + offset], owner


def _cells(
    points: NDArray[np.float64], cell: float
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Group points ``(n, 3)`` by grid cell: ``group (n,)``, and the CSR ``starts (g + 1,)``,
    ``order (n,)`` of the members of each group."""
    _, group = np.unique(np.floor(points / cell).astype(np.int64), axis=0, return_inverse=True)
    group = group.ravel()
    order = np.argsort(group, kind="stable")
    starts = np.searchsorted(group[order], np.arange(int(group.max()) + 2))
    return group, starts, order


@dataclass(frozen=True)
class Clearances:
    """Outcome of :meth:`PoseBound.classify` for ``m`` candidates.

    Attributes
    ----------
    value
        ``(m,)`` mm: at least the clearance exactly where the candidate keeps it; a lower bound
        of the distance there, an upper bound (FCL's distance of one piece) where it does not: the
        distance itself is not known (the search measures the whole tool where it needs it).
    fcl_queries
        FCL distance queries asked (of pieces).
    bound_free
        Candidates shown free by the sphere bound alone (no FCL query).
    """

    value: NDArray[np.float64]
    fcl_queries: int
    bound_free: int = 0


class PoseBound:
    """Free-or-short classification of weld-pose candidates (module docstring).

    Parameters
    ----------
    part
        The part (mm).
    tool
        The tool (mm, TCP frame).
    radius
        mm: the contact-zone radius (the pieces are of the tool outside it).
    clearance
        mm: what a free candidate keeps from the part (> 0).
    """

    def __init__(self, part: trimesh.Trimesh, tool: Tool, radius: float, clearance: float) -> None:
        if not clearance > 0:
            raise ValueError("the bound classifies against a clearance > 0")
        self.clearance = float(clearance)
        self.pieces = ToolPieces.of(tool, radius)
        self.distance = SurfaceDistance(part)
        self.lo, self.hi = np.asarray(part.bounds, dtype=np.float64)
        self.req = fcl.DistanceRequest()

    def _lower(self, W: NDArray[np.float64], need: NDArray[np.float64]) -> NDArray[np.float64]:
        """``(n,)`` mm: lower bounds of points' ``(n, 3)`` distances to the part: the distance to
        its bounding box, and where that is not above ``need (n,)``, open3d's exact distance
        less its round-off (about 1 us a point)."""
        d = np.linalg.norm(np.maximum(np.maximum(self.lo - W, W - self.hi), 0.0), axis=1)
        near = np.flatnonzero(d < need)
        if len(near):
            d[near] = np.maximum(d[near], self.distance(W[near]) - self.distance.tolerance)
        return d

    def pieces_near(
        self, P: NDArray[np.float64], Rs: NDArray[np.float64]
    ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        """The pieces that may come within the clearance, for the tool at TCP ``P (m, 3)`` with
        rotations ``Rs (m, 3, 3)``: ``(candidate (u,), piece (u,), lower bound (u,))`` of each,
        opened coarse to fine, and ``(m,)`` the least lower
        bound of the spheres cleared per candidate (``inf`` where none)."""
        pc, C = self.pieces, self.clearance
        m = len(Rs)
        which = np.tile(np.arange(len(pc.radii[0])), m)
        owner = np.repeat(np.arange(m), len(pc.radii[0]))
        cleared = np.full(m, np.inf)
        last = len(pc.radii) - 1
        for level in range(last + 1):
            c, r = pc.centres[level][which], pc.radii[level][which]
            W = np.einsum("nij,nj->ni", Rs[owner], c) + P[owner]
            lb = self._lower(W, r + C) - r
            ok = lb >= C
            np.minimum.at(cleared, owner[ok], lb[ok])
            which, owner, lb = which[~ok], owner[~ok], lb[~ok]
            if level == last or len(which) == 0:
                return owner, which, lb, cleared
            which, pos = pc.open(level, which)
            owner = owner[pos]
        raise AssertionError("unreachable")

    def _piece(self, k: int, tf: fcl.Transform, part_obj: fcl.CollisionObject) -> float:
        """mm: FCL's distance from piece ``k`` at ``tf`` to the part object."""
        obj = self.pieces.objects[k]
        obj.setTransform(tf)
        return float(fcl.distance(obj, part_obj, self.req, fcl.DistanceResult()))

    def classify(
        self,
        part_objs: list[fcl.CollisionObject | None],
        P: NDArray[np.float64],
        Rs: NDArray[np.float64],
        *,
        first_free: bool = False,
    ) -> Clearances:
        """Free or short, for candidates at TCP ``P (m, 3)`` mm with rotations ``Rs (m, 3, 3)``
        that do not collide with their ``part_objs`` (``m`` of the search's part objects;
        module docstring). With ``first_free``, only up to the first free candidate in the
        given order: the rest are left NaN (the search measures in order and stops there)."""
        P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
        Rs = np.asarray(Rs, dtype=np.float64).reshape(-1, 3, 3)
        m = len(Rs)
        value = np.full(m, np.inf)
        asked = 0
        live = np.flatnonzero([o is not None for o in part_objs])
        owner = piece = lb = np.zeros(0, dtype=np.int64)
        if len(live):
            owner, piece, lb, value[live] = self.pieces_near(P[live], Rs[live])
            owner = live[owner]
        bare = 0
        order = np.lexsort((lb, owner))
        starts = np.searchsorted(owner[order], np.arange(m + 1))
        for a in range(m):
            mine = order[starts[a] : starts[a + 1]]
            bare += len(mine) == 0 and a in live
            tf = fcl.Transform(Rs[a], P[a]) if len(mine) else None
            for k in piece[mine]:
                asked += 1
                value[a] = min(value[a], self._piece(int(k), tf, part_objs[a]))
                if value[a] < self.clearance:
                    break
            if first_free and value[a] >= self.clearance:
                value[a + 1 :] = np.nan
                break
        return Clearances(value, asked, int(bare))
