"""What lets the robot-robot interference check skip FCL queries whose answer it already knows.

The check (:mod:`weldplan.multi.interference`) halves the sample ranges of two motions and asks,
at each node (a range of each motion, body ``p`` of one robot against body ``q`` of the other),
the FCL distance ``d`` of the two bodies at the ranges' middle samples; with ``R`` mm, how far
the two bodies can be from there over their ranges, the node is

* **proven clear** when ``d - R >= clearance``,
* a **witness** when ``d < clearance`` (the two motions conflict),
* **halved** otherwise (or, two single samples, a conflict not proven clear).

Each body is covered by small spheres: its triangles cut to edges of at most
:data:`FINE_EDGE_MM` (trimesh's ``subdivide_to_size``: the same surface), grouped by a grid
on their centroids (:func:`weldplan.geometry.spherecover.sphere_cover`), and the spheres in
groups, each inside a larger one (:func:`weldplan.robot.collision.motionbound.sphere_groups`);
each sphere holds a point of the surface. At the two middle samples the spheres give, with no
FCL query,

* a lower bound ``lb <= d``: the least gap between a sphere of one body and one of the other
  (every point of a body lies in one of its spheres; the small spheres are asked only in the
  groups whose spheres come close enough to matter);
* an upper bound ``ub >= d``: the least distance between the points held by the
  :data:`UB_PAIRS` sphere pairs of least gap (two points of the two bodies).

So ``lb - R >= clearance`` proves the node clear, and ``lb >= clearance`` with
``ub - R < clearance`` says it is halved, both as ``d`` would have, by a margin of
:data:`EPS_MM`: the FCL query is skipped and the search goes on exactly as with it. The
verdicts, the witnesses and their distances are those of the check without the spheres
(``InterferenceSettings(prune=False)``); only the FCL queries that would have settled nothing
else are left out (the sphere covers of Quinlan, "Efficient distance computation between
non-convex objects", ICRA 1994; the bisection is conservative advancement's argument).

Where two single samples are met (a leaf), ``d`` is recorded for a conflict not proven clear,
so a leaf is skipped only when it is proven clear.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from weldplan.geometry.spherecover import sphere_cover
from weldplan.robot.collision.bodies import Body
from weldplan.robot.collision.motionbound import sphere_groups

#: mm: the margin by which a sphere bound must settle a node before its FCL query is skipped
#: (far above FCL's round-off on meshes of metres, far below any clearance)
EPS_MM = 1e-6
#: sphere pairs of least gap whose points bound the distance from above
UB_PAIRS = 64
#: mm: the longest triangle edge of a body's small spheres' mesh, and their grid cell
FINE_EDGE_MM = 40.0
FINE_CELL_MM = 40.0
#: mm: the grid cell of the groups of small spheres (each group inside one sphere)
GROUP_CELL_MM = 150.0
#: small sphere pairs one node may compare (beyond, the FCL query decides), and the pairs of
#: groups whose small spheres are compared at once (the closest first)
MAX_FINE_PAIRS = 400_000
FINE_CHUNK = 8
#: a pair of bodies is asked to the spheres only when one of them has at least this many
#: triangles (a tool): FCL on two links of a few hundred triangles each is cheap (on two
#: synthetic crossing pairs with the spot gun, asking the spheres for link pairs too saved 14
#: and 20 of 718 and 45 queries, and no time)
MIN_TRIANGLES = 2000

#: covers made (:func:`body_cover`), by the digest of their mesh (:func:`mesh_key`), at most
#: MAX_COVERS: made once per process for every robot of one model
COVERS: dict[str, Cover] = {}
MAX_COVERS = 64

#: what a node's sphere bounds say (:func:`settled`)
UNKNOWN, CLEAR, HALVE = 0, 1, 2


@dataclass(frozen=True, eq=False)
class Cover:
    """A body's small spheres in groups, and one point of its surface in each sphere, in its
    link's frame (module docstring).

    Attributes
    ----------
    centres, radii, points
        ``(s, 3)`` mm, ``(s,)`` mm, ``(s, 3)`` mm: the small spheres, sorted by group, and per
        sphere the centroid of one of its triangles.
    group_centres, group_radii, group_points
        ``(g, 3)`` mm, ``(g,)`` mm, ``(g, 3)`` mm: each group's sphere (it holds its members'
        spheres) and its member's point nearest its centre.
    starts
        ``(g + 1,)``: group ``k``'s spheres are ``starts[k]:starts[k + 1]``.
    """

    centres: NDArray[np.float64]
    radii: NDArray[np.float64]
    points: NDArray[np.float64]
    group_centres: NDArray[np.float64]
    group_radii: NDArray[np.float64]
    group_points: NDArray[np.float64]
    starts: NDArray[np.int64]


def _nearest(points: NDArray, group: NDArray, centres: NDArray) -> NDArray[np.int64]:
    """``(g,)``: per group ``0..g-1`` the index of its point nearest its centre."""
    dist = np.linalg.norm(points - centres[group], axis=1)
    order = np.lexsort((dist, group))  # per group, its nearest point first
    return order[np.searchsorted(group[order], np.arange(len(centres)))]


def worth_asking(a: Body, b: Body) -> bool:
    """Whether the spheres are asked for the pair of bodies ``a``, ``b``
    (:data:`MIN_TRIANGLES`)."""
    return max(len(a.faces), len(b.faces)) >= MIN_TRIANGLES


def body_cover(body: Body) -> Cover:
    """The :class:`Cover` of ``body`` (its mesh in its link's frame, mm); made once per mesh
    (:data:`COVERS`: the robots of one model share their links')."""
    v = np.ascontiguousarray(body.vertices, dtype=np.float64)
    f = np.ascontiguousarray(body.faces, dtype=np.int64)
    return cached(COVERS, mesh_key(v, f), lambda: _make_cover(v, f))


def mesh_key(v: NDArray[np.float64], f: NDArray[np.int64]) -> str:
    """The digest of a mesh ``v (n, 3)``, ``f (m, 3)`` (its bytes as float64 and int64)."""
    v = np.ascontiguousarray(v, dtype=np.float64)
    f = np.ascontiguousarray(f, dtype=np.int64)
    return hashlib.sha256(v.tobytes() + f.tobytes()).hexdigest()


def cached(table: dict[str, Any], key: str, make: Callable[[], Any]) -> Any:
    """``table[key]``, made by ``make()`` when missing; the oldest entries dropped beyond
    :data:`MAX_COVERS`."""
    got = table.get(key)
    if got is None:
        got = make()
        while len(table) >= MAX_COVERS:
            table.pop(next(iter(table)))
        table[key] = got
    return got


def _make_cover(v: NDArray[np.float64], f: NDArray[np.int64]) -> Cover:
    import trimesh

    v, f = trimesh.remesh.subdivide_to_size(v, f, FINE_EDGE_MM, max_iter=64)
    c, r, g = sphere_cover(v, f, FINE_CELL_MM)
    _, first = np.unique(g, return_index=True)  # a triangle of each sphere: its centroid
    pts = v[f[first]].mean(axis=1)
    member, gc, gr, order, starts = sphere_groups(c, r, GROUP_CELL_MM)
    c, r, pts, member = c[order], r[order], pts[order], member[order]
    gp = pts[_nearest(pts, member, gc)]
    bounds = np.append(starts, len(r)).astype(np.int64)
    return Cover(c, r, pts, gc, gr, gp, bounds)


def _placed(x: NDArray[np.float64], T: NDArray[np.float64]) -> NDArray[np.float64]:
    return x @ T[:3, :3].T + T[:3, 3]


def _gaps(A: NDArray, ra: NDArray, B: NDArray, rb: NDArray) -> NDArray[np.float64]:
    """``(a, b)`` mm: the gaps between spheres ``A (a, 3)``, ``ra`` and ``B (b, 3)``, ``rb``."""
    gap = np.sqrt(((A[:, None, :] - B[None, :, :]) ** 2).sum(axis=2))
    gap -= ra[:, None] + rb[None, :]
    return gap


def _upper(Pa: NDArray, Pb: NDArray, gap: NDArray) -> float:
    """mm: the least distance between the points ``Pa (a, 3)``, ``Pb (b, 3)`` of the
    :data:`UB_PAIRS` sphere pairs of least ``gap (a, b)``: a distance between two points of the
    bodies, so at least theirs."""
    flat = gap.ravel()
    k = min(UB_PAIRS, flat.size)
    pick = np.argpartition(flat, k - 1)[:k] if k < flat.size else np.arange(flat.size)
    i, j = np.divmod(pick, gap.shape[1])
    return float(np.linalg.norm(Pa[i] - Pb[j], axis=1).min())


@dataclass
class _Placed:
    """Two covers placed at their frames: the groups' gaps, the small spheres on demand."""

    ca: Cover
    Ta: NDArray[np.float64]
    cb: Cover
    Tb: NDArray[np.float64]
    gap: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 0)))
    members: dict[tuple[int, int], tuple[NDArray, NDArray, int]] = field(default_factory=dict)

    def groups(self) -> float:
        """mm: the least gap between the groups' spheres (and keeps them all)."""
        self.gap = _gaps(
            _placed(self.ca.group_centres, self.Ta), self.ca.group_radii,
            _placed(self.cb.group_centres, self.Tb), self.cb.group_radii,
        )  # fmt: skip
        return float(self.gap.min())

    def group_upper(self) -> float:
        """mm: an upper bound from the groups' points."""
        Pa, Pb = _placed(self.ca.group_points, self.Ta), _placed(self.cb.group_points, self.Tb)
        return _upper(Pa, Pb, self.gap)

    def _close(self, below: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """The pairs of groups whose spheres come within ``below`` mm, the closest first."""
        ia, ib = np.nonzero(self.gap < below)
        order = np.argsort(self.gap[ia, ib], kind="stable")
        return ia[order], ib[order]

    def _members(self, side: int, g: int) -> tuple[NDArray, NDArray, int]:
        """Group ``g``'s small spheres of body ``side`` (0: a, 1: b) placed: ``(centres
        (n, 3) mm, radii (n,) mm, index of the first)``, placed once per node."""
        key = (side, int(g))
        if key not in self.members:
            c, T = (self.ca, self.Ta) if side == 0 else (self.cb, self.Tb)
            lo, hi = int(c.starts[g]), int(c.starts[g + 1])
            self.members[key] = (_placed(c.centres[lo:hi], T), c.radii[lo:hi], lo)
        return self.members[key]

    def _fine(self, ga: int, gb: int) -> NDArray[np.float64]:
        """``(na, nb)`` mm: the gaps between the small spheres of group ``ga`` of a and group
        ``gb`` of b."""
        A, ra, _ = self._members(0, ga)
        B, rb, _ = self._members(1, gb)
        return _gaps(A, ra, B, rb)

    def at_least(self, bound: float) -> bool:
        """Whether no small sphere of one body comes within ``bound`` mm of one of the other
        (the group pairs asked closest first: the first gap below ``bound`` ends it);
        ``False`` also beyond :data:`MAX_FINE_PAIRS` pairs."""
        ia, ib = self._close(bound)
        asked = 0
        for ga, gb in zip(ia.tolist(), ib.tolist(), strict=True):
            gap = self._fine(ga, gb)
            if float(gap.min()) < bound:
                return False
            asked += gap.size
            if asked > MAX_FINE_PAIRS:
                return False
        return True

    def fine_upper(self, below: float) -> float:
        """mm: an upper bound from the small spheres' points of the :data:`FINE_CHUNK` group
        pairs of least gap (``inf`` when none comes within ``below`` mm)."""
        ia, ib = self._close(below)
        ub = np.inf
        for ga, gb in zip(ia[:FINE_CHUNK].tolist(), ib[:FINE_CHUNK].tolist(), strict=True):
            gap = self._fine(ga, gb)
            la, lb = self._members(0, ga)[2], self._members(1, gb)[2]
            i, j = np.unravel_index(int(np.argmin(gap)), gap.shape)
            pa = _placed(self.ca.points[la + i : la + i + 1], self.Ta)
            pb = _placed(self.cb.points[lb + j : lb + j + 1], self.Tb)
            ub = min(ub, float(np.linalg.norm(pa - pb)))
        return ub


def sphere_bounds(
    ca: Cover, Ta: NDArray[np.float64], cb: Cover, Tb: NDArray[np.float64]
) -> tuple[float, float]:
    """``(lb, ub)`` mm: bounds on the distance of two bodies (their covers ``ca``, ``cb``)
    placed at ``Ta``, ``Tb`` ``(4, 4)`` mm (module docstring), every pair of small spheres
    compared."""
    A, Pa = _placed(ca.centres, Ta), _placed(ca.points, Ta)
    B, Pb = _placed(cb.centres, Tb), _placed(cb.points, Tb)
    lb = ub = np.inf
    for k in range(0, len(A), 256):
        gap = _gaps(A[k : k + 256], ca.radii[k : k + 256], B, cb.radii)
        lb, ub = min(lb, float(gap.min())), min(ub, _upper(Pa[k : k + 256], Pb, gap))
    return lb, ub


def settled(
    ca: Cover, Ta: NDArray[np.float64], cb: Cover, Tb: NDArray[np.float64],
    reach: float, clearance: float, leaf: bool,
) -> int:  # fmt: skip
    """What the spheres of two bodies at ``Ta``, ``Tb`` ``(4, 4)`` mm (their links' frames) say
    of a node whose bodies can be ``reach`` mm from there (module docstring): :data:`CLEAR`,
    :data:`HALVE` (never for a ``leaf``) or :data:`UNKNOWN` (the FCL query decides).

    ``CLEAR`` needs ``lb >= clear``; ``HALVE`` needs ``lb >= low`` and ``ub < high``; the
    groups' spheres are asked first, the small spheres only in the groups that come within
    the bound asked."""
    clear, low = clearance + reach + EPS_MM, clearance + EPS_MM
    high = clearance + reach - EPS_MM
    p = _Placed(ca, Ta, cb, Tb)
    if p.groups() >= clear:
        return CLEAR
    if leaf:
        return CLEAR if p.at_least(clear) else UNKNOWN
    if p.group_upper() < high:  # not clear: halved if nothing comes within the clearance
        return HALVE if p.at_least(low) else UNKNOWN
    if p.at_least(clear):
        return CLEAR
    if not p.at_least(low):
        return UNKNOWN
    return HALVE if p.fine_upper(clear) < high else UNKNOWN
