"""A sound, fast lower bound of the swept check's slack: sphere covers of the tool against the
part's distance table, for the SE(3) re-plan's states and motions.

Why. The SE(3) re-plan (:mod:`weldplan.tool.se3_replan`) asks OMPL to plan the whole tool. Each
of its validity checks was an exact python-fcl distance of the 23k-triangle gun a few mm from a
flange (about 5 ms), so RRT-Connect saw 26-36 states in 10 s and starved. Most of the states and
motions it asks about are far from the part or plainly through it; only a few need FCL.

The bound. The tool outside its contact zone and the tool in its zone (the checker's two
bodies, :class:`~weldplan.tool.sweep.SweepChecker`) are each covered by spheres on
:data:`LEVELS` grids (fine spheres of triangles cut to :data:`COVER_EDGE_MM`, each coarser
sphere holding the finer spheres whose centres share its cell: a tree). A sphere of radius
``r`` whose centre is at distance ``d`` from the part keeps every point of it at least
``d - r`` away. ``d`` is bounded below by the part's distance table
(:class:`~weldplan.geometry.distbound.DistanceBound`: 1-Lipschitz, so a grid node's exact distance
less the way to it), and where that does not decide by open3d's exact distance less its
round-off. So

    slack(p, R) >= min over spheres i of  d(R c_i + p) - r_i - need_i

with ``need_i`` the clearance for the outside body, and for the zone body 0 when weld spots are
exempt (it must only not touch the part outside their spheres: the whole part is a superset, so
its distance is a lower bound) else the clearance. A coarse sphere that clears is not opened; one
that does not is replaced by its children.

Motions. Along a motion (straight TCP segment, slerp; :mod:`weldplan.tool.sweep`) a sphere centre
``c`` moves at most ``V = |dp| + theta |c|`` per unit of the parameter (a tighter
:func:`~weldplan.tool.sweep.motion_bound` for points near the TCP). Its distance is V-Lipschitz in
the parameter, so over an interval ``[a, b]`` with end distances ``Da``, ``Db`` it stays at least
``(Da + Db - V (b - a)) / 2``. :meth:`SweepBound.motion_clear` samples the motion on a grid,
proves every (interval, sphere) pair with that bound, opens the spheres that fail, and halves the
intervals that still fail up to :data:`MAX_HALVINGS` times. It proves the slack at least
``margin`` (the checker's ``min_step``) everywhere on the motion; then the exact conservative
advancement would pass it too (every sample's slack is at least ``min_step``, so it never
stops short and its steps are at least ``min_step / L``: within its sample budget). Anything
undecided is left to the exact check: the bound only ever says "free", never "blocked".
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.distance import SurfaceDistance
from weldplan.geometry.distbound import DistanceBound
from weldplan.geometry.spherecover import sphere_cover
from weldplan.tool.model import Tool
from weldplan.tool.sweep import _interpolator, tool_zone

log = logging.getLogger(__name__)

#: a motion's poses at parameters ``(k,)``: positions ``(k, 3)`` mm, rotations ``(k, 3, 3)``
Interpolator = Callable[[ArrayLike], tuple[NDArray[np.float64], NDArray[np.float64]]]

#: mm: the cells of the sphere tree, finest first (measured on the shared gun outside its zone:
#: 6,665 spheres of median radius 9 mm at 10 mm, 1,002 at 25 mm, 191 at 60 mm)
LEVELS = (10.0, 25.0, 60.0)
#: mm: triangles are cut to edges below this before the finest cover (a long sliver's sphere
#: would be as large as the sliver)
COVER_EDGE_MM = 10.0
#: mm: a motion's first grid is fine enough that no sphere centre moves farther between samples
MOTION_GRID_MM = 40.0
#: halvings of a motion's undecided intervals before it is left to the exact check
MAX_HALVINGS = 4
#: (interval, sphere) pairs a motion may still have open before a halving (more: the motion
#: runs close to the part, and the advancement, :mod:`weldplan.tool.sweep_fast`, is cheaper)
MAX_PAIRS = 20_000
#: rad added to a motion's rotation angle (``acos`` near 1 loses about 1e-8 rad)
THETA_PAD = 1e-7


@dataclass(frozen=True)
class SphereTree:
    """Spheres that hold a body, on levels from coarse to fine.

    Attributes
    ----------
    centres, radii
        Per level (coarsest first): ``(s_l, 3)`` mm in the TCP frame and ``(s_l,)`` mm.
    children
        Per level but the finest: for each sphere the indices of the next finer level's spheres
        it holds (CSR: ``starts (s_l + 1,)``, ``index (s_{l+1},)``).
    """

    centres: tuple[NDArray[np.float64], ...]
    radii: tuple[NDArray[np.float64], ...]
    children: tuple[tuple[NDArray[np.int64], NDArray[np.int64]], ...]

    @classmethod
    def build(
        cls, vertices: NDArray[np.float64], faces: NDArray[np.int64], levels: tuple[float, ...]
    ) -> SphereTree:
        """The tree of a mesh ``(n, 3)`` mm, ``(m, 3)``: the finest level by
        :func:`~weldplan.geometry.spherecover.sphere_cover` on triangles cut to
        :data:`COVER_EDGE_MM`, each coarser sphere the bounding sphere of the finer spheres
        whose centres fall in one of its cells (so it holds them, and they hold the triangles)."""
        v, f = trimesh.remesh.subdivide_to_size(
            vertices, faces, max_edge=COVER_EDGE_MM, max_iter=30
        )
        c, r, _ = sphere_cover(np.asarray(v), np.asarray(f), levels[0])
        centres, radii, children = [c], [r], []
        for cell in levels[1:]:
            key = np.floor(c / cell).astype(np.int64)
            _, group = np.unique(key, axis=0, return_inverse=True)
            group = group.ravel()
            g = int(group.max()) + 1
            lo = np.full((g, 3), np.inf)
            hi = np.full((g, 3), -np.inf)
            np.minimum.at(lo, group, c - r[:, None])
            np.maximum.at(hi, group, c + r[:, None])
            cc = (lo + hi) / 2
            rr = np.zeros(g)
            np.maximum.at(rr, group, np.linalg.norm(c - cc[group], axis=1) + r)
            order = np.argsort(group, kind="stable")
            starts = np.searchsorted(group[order], np.arange(g + 1))
            children.append((starts.astype(np.int64), order.astype(np.int64)))
            c, r = cc, rr * (1 + 1e-9) + 1e-9
            centres.append(c)
            radii.append(r)
        return cls(tuple(centres[::-1]), tuple(radii[::-1]), tuple(children[::-1]))

    def open(self, level: int, which: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray]:
        """The children of spheres ``which`` of ``level``: ``(child indices (k,), position in
        which (k,))``."""
        starts, index = self.children[level]
        n = starts[which + 1] - starts[which]
        owner = np.repeat(np.arange(len(which)), n)
        first = np.repeat(starts[which], n)
        offset = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        return index[first + offset], owner


class SweepBound:
    """Lower bounds of :meth:`SweepChecker.slack <weldplan.tool.sweep.SweepChecker.slack>` from
    sphere trees of the tool and the part's distance table (module docstring).

    Parameters
    ----------
    part, tool
        The part and the tool (mm).
    clearance, contact_radius
        mm, the checker's.
    """

    def __init__(
        self, part: trimesh.Trimesh, tool: Tool, clearance: float, contact_radius: float
    ) -> None:
        self.clearance = float(clearance)
        self.distance = SurfaceDistance(part)
        self.table = DistanceBound(self.distance, *np.asarray(part.bounds, dtype=np.float64))
        key = ("sphere_trees", float(contact_radius), tool.tip_cone, LEVELS)
        if key not in tool._cache:  # the trees depend on the tool and its zone only
            vo, fo = tool.outside_zone(contact_radius)
            vz, fz = tool_zone(tool, contact_radius)
            zone = SphereTree.build(vz, fz, LEVELS) if len(fz) else None
            tool._cache[key] = (SphereTree.build(vo, fo, LEVELS), zone)
        self.outside, self.zone = tool._cache[key]
        #: decisions by the bound, and the exact distances it asked open3d for
        self.stats = {"states": 0, "states_clear": 0, "motions": 0, "motions_clear": 0, "exact": 0}

    def _dist(self, points: NDArray[np.float64], need: NDArray, exact: bool = True) -> NDArray:
        """``(n,)`` mm: lower bounds of the points' ``(n, 3)`` distances to the part: the table's,
        and (``exact``) open3d's exact distance less its round-off where the table's is not
        above ``need``."""
        d = self.table.lower(points)
        low = np.flatnonzero(d <= need) if exact else ()
        if len(low):
            self.stats["exact"] += len(low)
            d[low] = np.maximum(d[low], self.distance(points[low]) - self.table.tol)
        return d

    def _bodies(self, exempt: bool) -> list[tuple[SphereTree, float]]:
        """The trees and what each must keep from the part (module docstring)."""
        out = [(self.outside, self.clearance)]
        if self.zone is not None:
            out.append((self.zone, 0.0 if exempt else self.clearance))
        return out

    def spheres(
        self, p: ArrayLike, R: ArrayLike, exempt: bool, floor: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
        """The tool at TCP ``p (3,)`` mm, ``R (3, 3)`` as spheres with a lower bound of their
        slack each, opened coarse to fine where that bound is below ``floor`` mm.

        Returns
        -------
        slack, lever
            ``(k,)`` mm: the spheres' slack bounds (at least ``floor``) and their centres'
            distances from the TCP (a motion moves a centre at most ``|dp| + theta lever``).
        open_lever
            mm: the largest ``|c| + r`` of the finest spheres still below ``floor`` (their
            points' lever), ``-1`` when there are none: then the bound decides the pose.
        """
        p = np.asarray(p, dtype=np.float64)
        R = np.asarray(R, dtype=np.float64)
        slacks, levers, open_lever = [], [], -1.0
        for tree, need in self._bodies(exempt):
            which = np.arange(len(tree.radii[0]))
            for level in range(len(tree.radii)):
                c0 = tree.centres[level][which]
                r = tree.radii[level][which]
                sl = self._dist(c0 @ R.T + p, r + need + floor) - r - need
                good = sl >= floor
                slacks.append(sl[good])
                levers.append(np.linalg.norm(c0[good], axis=1))
                bad = which[~good]
                if len(bad) == 0:
                    break
                if level == len(tree.radii) - 1:
                    lever = (
                        np.linalg.norm(tree.centres[level][bad], axis=1) + tree.radii[level][bad]
                    )
                    open_lever = max(open_lever, float(lever.max()))
                    break
                which, _ = tree.open(level, bad)
        return np.concatenate(slacks), np.concatenate(levers), open_lever

    def state_clear(self, p: ArrayLike, R: ArrayLike, exempt: bool) -> bool:
        """Whether the bound proves the tool at TCP ``p (3,)`` mm, ``R (3, 3)`` clears what it
        must (slack >= 0; ``exempt``: weld spots are exempt, as the checker's ``exempt``).
        ``False`` means undecided, not blocked."""
        self.stats["states"] += 1
        clear = self.spheres(p, R, exempt, 0.0)[2] < 0
        self.stats["states_clear"] += clear
        return clear

    def motion_clear(
        self,
        p0: ArrayLike,
        q0: ArrayLike,
        p1: ArrayLike,
        q1: ArrayLike,
        exempt: bool,
        margin: float,
    ) -> bool:
        """Whether the bound proves the slack at least ``margin`` mm all along the motion
        ``(p0, q0) -> (p1, q1)`` (TCP mm, wxyz; module docstring). ``False``: undecided."""
        self.stats["motions"] += 1
        at = _interpolator(p0, q0, p1, q1)
        dp = float(np.linalg.norm(np.asarray(p1, dtype=np.float64) - np.asarray(p0, np.float64)))
        _, R0 = at([0.0])
        _, R1 = at([1.0])
        cos = (np.trace(R0[0].T @ R1[0]) - 1.0) / 2.0
        theta = math.acos(min(1.0, max(-1.0, cos))) + THETA_PAD
        for tree, need in self._bodies(exempt):
            if not self._tree_clear(tree, need + margin, at, dp, theta):
                return False
        self.stats["motions_clear"] += 1
        return True

    def _tree_clear(
        self, tree: SphereTree, need: float, at: Interpolator, dp: float, theta: float
    ) -> bool:
        """One body's part of :meth:`motion_clear`: (interval, sphere) pairs proved coarse to
        fine, undecided intervals halved."""
        reach = np.linalg.norm(tree.centres[0], axis=1) + tree.radii[0]
        n = max(2, math.ceil((dp + theta * float(reach.max())) / MOTION_GRID_MM) + 1)
        s = np.linspace(0.0, 1.0, n)
        # pairs: interval ends (a, b), level, sphere; distances at the ends filled as needed
        a, b = s[:-1], s[1:]
        k = len(a)
        m = len(tree.radii[0])
        a, b = np.repeat(a, m), np.repeat(b, m)
        sph = np.tile(np.arange(m), k)
        level = 0
        halvings = 0
        while len(a):
            ok = self._pairs_clear(tree, level, sph, a, b, need, at, dp, theta)
            a, b, sph = a[~ok], b[~ok], sph[~ok]
            if not len(a):
                return True
            if level < len(tree.radii) - 1:
                sph, owner = tree.open(level, sph)
                a, b = a[owner], b[owner]
                level += 1
                continue
            if halvings == MAX_HALVINGS or len(a) > MAX_PAIRS:
                return False
            mid = (a + b) / 2
            a, b = np.concatenate([a, mid]), np.concatenate([mid, b])
            sph = np.concatenate([sph, sph])
            halvings += 1
        return True

    def _pairs_clear(
        self,
        tree: SphereTree,
        level: int,
        sph: NDArray[np.int64],
        a: NDArray[np.float64],
        b: NDArray[np.float64],
        need: float,
        at: Interpolator,
        dp: float,
        theta: float,
    ) -> NDArray[np.bool_]:
        """``(n,) bool``: whether sphere ``sph`` of ``level`` keeps ``need`` mm over ``[a, b]``
        (pairwise Lipschitz bound, module docstring)."""
        c = tree.centres[level][sph]
        r = tree.radii[level][sph]
        V = dp + theta * np.linalg.norm(c, axis=1)
        half = V * (b - a) / 2
        want = r + need + half
        ends, inv = np.unique(np.concatenate([a, b]), return_inverse=True)
        P, Rs = at(ends)
        ia, ib = inv[: len(a)], inv[len(a) :]
        wa = np.einsum("nij,nj->ni", Rs[ia], c) + P[ia]
        wb = np.einsum("nij,nj->ni", Rs[ib], c) + P[ib]
        da = self._dist(wa, want, exact=False)
        db = self._dist(wb, want, exact=False)
        return (da + db) / 2 - half >= r + need
