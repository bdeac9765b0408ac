"""A sound, fast lower bound of the swept check's slack: sphere covers of the tool against the
part's distance table, for the SE(3) re-plan's states and motions.

Why. The SE(3) re-plan (:mod:`weldplan.tool.transitions.se3_replan`) asks OMPL to plan the whole
tool. Each of its validity checks was an exact python-fcl distance of the 23k-triangle gun a few mm
from a flange (about 5 ms), so RRT-Connect saw 26-36 states in 10 s and starved. Most of the states
and motions it asks about are far from the part or plainly through it; only a few need FCL.

The bound. The tool outside its contact zone and the tool in its zone (the checker's two
bodies, :class:`~weldplan.tool.transitions.SweepChecker`) are each covered by spheres on
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

Motions. Along a motion (straight TCP segment, slerp; :mod:`weldplan.tool.transitions.sweep`) a
sphere centre ``c`` moves at most ``V = |dp| + theta |c|`` per unit of the parameter (a tighter
:func:`~weldplan.tool.transitions.motion_bound` for points near the TCP), so a sphere whose slack
bound is ``sl`` at a sample keeps slack over ``sl / V`` of the parameter either way.
:meth:`SweepBound.rates` gives, for many samples of one motion at once, the least of these
ratios and the spheres the bound could not decide; the coarse-to-fine advancement of
:mod:`weldplan.tool.transitions.sweep_fast` covers the motion with them and asks FCL only at the
samples the bound leaves undecided. The bound only ever says "free", never "blocked".
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from weldplan.geometry.distance import SurfaceDistance
from weldplan.geometry.distbound import DistanceBound
from weldplan.geometry.spherecover import cell_groups, group_reduce, sphere_cover
from weldplan.tool.model.tool import Tool
from weldplan.tool.transitions.sweep import tool_zone

log = logging.getLogger(__name__)

#: a motion's poses at parameters ``(k,)``: positions ``(k, 3)`` mm, rotations ``(k, 3, 3)``
Interpolator = Callable[[ArrayLike], tuple[NDArray[np.float64], NDArray[np.float64]]]

#: mm: the cells of the sphere tree, finest first (measured on the shared gun outside its zone:
#: 6,665 spheres of median radius 9 mm at 10 mm, 1,002 at 25 mm, 191 at 60 mm)
LEVELS = (10.0, 25.0, 60.0)
#: mm: triangles are cut to edges below this before the finest cover (a long sliver's sphere
#: would be as large as the sliver)
COVER_EDGE_MM = 10.0
#: nodes of the part's distance table (:class:`~weldplan.geometry.distbound.DistanceBound`; 8.6
#: mm cells on the demo part): the re-plans fill nearly all of it, and a finer one (1.5 M
#: nodes, 5.5 mm) cost more to fill than the exact distances it saved
TABLE_NODES = 400_000
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
            group = cell_groups(np.floor(c / cell).astype(np.int64))
            g = int(group.max()) + 1
            lo = group_reduce(np.minimum, c - r[:, None], group, g)
            hi = group_reduce(np.maximum, c + r[:, None], group, g)
            cc = (lo + hi) / 2
            rr = group_reduce(np.maximum, np.linalg.norm(c - cc[group], axis=1) + r, group, g)
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
    """Lower bounds of :meth:`SweepChecker.slack <weldplan.tool.transitions.SweepChecker.slack>`
    from sphere trees of the tool and the part's distance table (module docstring).

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
        self.table = DistanceBound(
            self.distance, *np.asarray(part.bounds, dtype=np.float64), max_nodes=TABLE_NODES
        )
        key = ("sphere_trees", float(contact_radius), tool.tip_cone, LEVELS)
        if key not in tool._cache:  # the trees depend on the tool and its zone only
            vo, fo = tool.outside_zone(contact_radius)
            vz, fz = tool_zone(tool, contact_radius)
            zone = SphereTree.build(vz, fz, LEVELS) if len(fz) else None
            tool._cache[key] = (SphereTree.build(vo, fo, LEVELS), zone)
        self.outside, self.zone = tool._cache[key]
        #: decisions by the bound, and the exact distances it asked open3d for
        self.stats = {"states": 0, "states_clear": 0, "exact": 0}

    def _dist(self, points: NDArray[np.float64], need: NDArray, exact: bool = True) -> NDArray:
        """``(n,)`` mm: lower bounds of the points' ``(n, 3)`` distances to the part: the table's,
        and (``exact``) open3d's exact distance less its round-off where the table's is not
        above ``need`` and its upper bound is (:meth:`DistanceBound.bounds
        <weldplan.geometry.distbound.DistanceBound.bounds>`: below it, the exact distance could
        not reach ``need`` either, so whether a point clears ``need`` is the same answer)."""
        d, up = self.table.bounds(points)
        low = np.flatnonzero((d <= need) & (up > need)) if exact else ()
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

    def rates(
        self,
        P: ArrayLike,
        Rs: ArrayLike,
        exempt: bool,
        floor: float,
        speed: tuple[float, float],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`spheres` at ``k`` poses of one motion at once (one tree walk, one distance
        query per level for all of them): TCP ``P (k, 3)`` mm, ``Rs (k, 3, 3)``.

        ``speed = (dp, theta)``: the motion's TCP travel (mm) and turn (rad), so that a sphere
        centre ``c`` moves at most ``V = dp + theta |c|`` per unit of the motion parameter.

        Returns
        -------
        rate
            ``(k,)``: the least ``slack / V`` over the spheres whose slack bound reached
            ``floor`` (``inf`` where none did): the parameter distance over which none of them
            can use its slack up, either way from the pose.
        least
            ``(k,)`` mm: the least slack bound of those spheres.
        open_lever
            ``(k,)`` mm: per pose, the largest ``|c| + r`` of the finest spheres still below
            ``floor`` (their points' lever), ``-1`` where there are none: the bound decides
            that pose alone.
        """
        P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
        Rs = np.asarray(Rs, dtype=np.float64).reshape(-1, 3, 3)
        dp, theta = speed
        k = len(P)
        rate, least = np.full(k, np.inf), np.full(k, np.inf)
        open_lever = np.full(k, -1.0)
        for tree, need in self._bodies(exempt):
            m = len(tree.radii[0])
            which, owner = np.tile(np.arange(m), k), np.repeat(np.arange(k), m)
            last = len(tree.radii) - 1
            for level in range(last + 1):
                c0, r = tree.centres[level][which], tree.radii[level][which]
                W = np.einsum("nij,nj->ni", Rs[owner], c0) + P[owner]
                # open3d only for the finest spheres: a coarse one the table cannot clear is
                # opened instead (its children are cheaper to bound than one exact distance)
                sl = self._dist(W, r + need + floor, exact=level == last) - r - need
                good = sl >= floor
                lever = np.linalg.norm(c0, axis=1)
                V = np.maximum(dp + theta * lever[good], 1e-12)
                np.minimum.at(rate, owner[good], sl[good] / V)
                np.minimum.at(least, owner[good], sl[good])
                bad = ~good
                if not bad.any():
                    break
                if level == last:
                    np.maximum.at(open_lever, owner[bad], lever[bad] + r[bad])
                    break
                which, pos = tree.open(level, which[bad])
                owner = owner[bad][pos]
        return rate, least, open_lever

    def state_clear(self, p: ArrayLike, R: ArrayLike, exempt: bool) -> bool:
        """Whether the bound proves the tool at TCP ``p (3,)`` mm, ``R (3, 3)`` clears what it
        must (slack >= 0; ``exempt``: weld spots are exempt, as the checker's ``exempt``).
        ``False`` means undecided, not blocked."""
        self.stats["states"] += 1
        clear = self.spheres(p, R, exempt, 0.0)[2] < 0
        self.stats["states_clear"] += clear
        return clear
