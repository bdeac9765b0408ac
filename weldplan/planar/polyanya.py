"""Polyanya: exact any-angle shortest paths on a navigation mesh, online, without preprocessing.

Cui, Harabor and Grastien, "Compromise-free pathfinding on a navigation mesh", IJCAI 2017.
The search is A* over *search nodes* ``(I, r)`` (the paper's "Search Nodes"): a root ``r``
(the start or a mesh vertex where the path last turned) and an interval ``I = [L, R]``, a
contiguous part of one polygon edge every point of which ``r`` sees. ``g`` is the length of the
path to ``r``; ``f = g + h`` with ``h`` the length of the shortest path from ``r`` through
``I`` to the goal (the paper's "Evaluating Search Nodes": the goal is reflected across the line
of ``I`` when it is on the root's side, then ``h = |r t'|`` when the segment ``r t'`` crosses
``I`` and ``|r p| + |p t'|`` through the nearer endpoint ``p`` otherwise). ``h`` never
overestimates and ``f`` never decreases along a search path, so the first final node popped is
optimal (the paper's optimality argument).

Successors (the paper's "Successors" and its Fig. 3): the rays from ``r`` through ``L`` and
``R`` are projected through the polygon ``P`` beyond ``I``. The part of ``P``'s far boundary
between the rays gives *observable* successors (same root, split at ``P``'s vertices so each
interval lies on one edge). When ``R`` (or ``L``) is the end of the edge and a corner, the far
boundary beyond the ray gives *non-observable* successors rooted at that vertex, with
``g' = g + |r R|``. A successor whose root lies on the line of its interval (a root at one of
the edge's ends: the path turned at that vertex and enters the next polygon directly) sees the
whole next polygon; its expansion makes every far edge observable.

Pruning (the paper's cul-de-sac and intermediate pruning, and its root-level closed list), each
exact and each switchable (``prune=False`` gives the same lengths; the tests check it):

* cul-de-sacs: a successor whose polygon has no exit but the edge it enters by, and holds no
  goal, is dropped;
* intermediate polygons: a node with exactly one successor has it expanded at once instead of
  going through the open list;
* root level: the best ``g`` seen for each root vertex is kept; a node whose root was reached
  more cheaply is dropped at generation and when popped.

The goal (the paper's final node): when the polygon beyond an interval holds the goal, the only
successor is the final node, ``f = g + h`` (``P`` is convex, so the goal is seen from the
interval's best point). Start and goal in one polygon: the straight segment. Points on an edge
or a vertex belong to every polygon around them; the start is expanded in each (its edges
through the start skipped). A point outside every polygon has no path (length ``inf``).

Deviations from the paper, named:

* corners: a path turns only at vertices beside an obstacle with more than 180 degrees of free
  space around them, or where obstacles touch (:attr:`NavMesh.corner`); the paper turns at any
  vertex beside an obstacle. A shortest path bends only around reflex obstacle corners, so the
  successors dropped cannot lie on one.
* ``h`` through an interval whose root lies on its line is the nearer endpoint's detour (exact
  there; the paper does not spell the case out).
* the root-level check is also made when a node is popped (a cheaper route to its root found
  after it was pushed), which only drops nodes the generation-time check would have dropped.
* tolerances are relative to the mesh's size (:data:`weldplan.planar.navmesh.REL_EPS`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.planar._polyanya_kernel import KernelMesh, Query, search
from weldplan.planar.navmesh import NavMesh

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PolyanyaResult:
    """One query's answer.

    Attributes
    ----------
    length
        Shortest path length (map units); ``inf`` when there is no path.
    points
        ``(k, 2)`` waypoints start, turning vertices, goal (empty when there is no path).
    expanded, generated
        Search nodes expanded and pushed (the paper's measures of effort).
    """

    length: float
    points: NDArray[np.float64]
    expanded: int = 0
    generated: int = 0

    @property
    def found(self) -> bool:
        return math.isfinite(self.length)


class Polyanya:
    """Polyanya queries on one :class:`NavMesh` (nothing is precomputed beyond the mesh's
    flat arrays; the search loop is compiled, :mod:`weldplan.planar._polyanya_kernel`).

    Parameters
    ----------
    mesh
        The navigation mesh.
    prune
        The paper's pruning (see the module docstring). ``False`` is the starved
        variant used by the tests: slower, same lengths.
    """

    def __init__(self, mesh: NavMesh, *, prune: bool = True) -> None:
        self.mesh = mesh
        self.prune = bool(prune)
        sizes = np.diff(mesh.ptr)
        self._kernel_mesh = KernelMesh(
            vx=np.asarray(mesh.vx, dtype=np.float64),
            vy=np.asarray(mesh.vy, dtype=np.float64),
            ptr=mesh.ptr,
            pv=mesh.pv,
            pnb=mesh.pnb,
            pop=mesh.popp,
            corner=np.asarray(mesh.corner, dtype=np.bool_),
            nexits=np.asarray(mesh.n_exits, dtype=np.int64),
            max_sides=int(sizes.max()) if len(sizes) else 3,
            eps=float(mesh.eps),
        )
        self._component = _components(mesh)

    def distance(self, start: ArrayLike, goal: ArrayLike) -> float:
        """Shortest path length, ``inf`` when none exists (or a point is off the mesh)."""
        return self.query(start, goal).length

    def query(self, start: ArrayLike, goal: ArrayLike) -> PolyanyaResult:
        """Shortest any-angle path from ``start (2,)`` to ``goal (2,)``."""
        m = self.mesh
        s = np.asarray(start, dtype=np.float64).reshape(2)
        t = np.asarray(goal, dtype=np.float64).reshape(2)
        spolys = m.locate(s)
        tpolys = m.locate(t)
        if not spolys or not tpolys:
            return PolyanyaResult(math.inf, np.zeros((0, 2)))
        if set(tpolys).intersection(spolys):  # one convex polygon: the straight segment
            return PolyanyaResult(float(np.hypot(*(t - s))), np.array([s, t]))
        comp = self._component
        if not set(comp[spolys].tolist()).intersection(comp[tpolys].tolist()):
            # no mesh path: answered without a search (the starved variant would otherwise
            # exhaust its open list, which without pruning can outgrow memory)
            return PolyanyaResult(math.inf, np.zeros((0, 2)))
        q = Query(
            sx=float(s[0]),
            sy=float(s[1]),
            tx=float(t[0]),
            ty=float(t[1]),
            spolys=np.asarray(spolys, dtype=np.int64),
            gpolys=np.asarray(tpolys, dtype=np.int64),
            prune=self.prune,
        )
        (length, pts), expanded, generated = search(self._kernel_mesh, q)
        if len(pts) > 2:  # a turn at an interval end that is also the root: listed once
            keep = np.ones(len(pts), dtype=bool)
            keep[1:] = np.abs(np.diff(pts, axis=0)).max(axis=1) > m.eps
            pts = pts[keep]
        return PolyanyaResult(float(length), pts, int(expanded), int(generated))


def polyanya_path(mesh: NavMesh, start: ArrayLike, goal: ArrayLike) -> PolyanyaResult:
    """One query on ``mesh`` (see :class:`Polyanya`)."""
    return Polyanya(mesh).query(start, goal)


def warm_up() -> float:
    """Run the compiled search once on a two-square mesh (compiling it on a fresh install, or
    loading it from numba's disk cache) and return the seconds it took, so benchmarks can keep
    that one-off cost out of their per-query figures."""
    import time

    t = time.perf_counter()
    V = [[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [0, 1]]
    mesh = NavMesh(V, [[0, 1, 4, 5], [1, 2, 3, 4]])
    for prune in (True, False):
        Polyanya(mesh, prune=prune).query([0.5, 0.5], [1.5, 0.5])
    return time.perf_counter() - t


def _components(mesh: NavMesh) -> NDArray[np.int64]:
    """``(n_polygons,)`` the connected component of each polygon, by shared edges."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = mesh.n_polygons
    owner = np.repeat(np.arange(n), np.diff(mesh.ptr))
    nb = np.asarray(mesh.pnb, dtype=np.int64)
    keep = nb >= 0
    graph = coo_matrix((np.ones(int(keep.sum())), (owner[keep], nb[keep])), shape=(n, n))
    return connected_components(graph, directed=False)[1].astype(np.int64)
