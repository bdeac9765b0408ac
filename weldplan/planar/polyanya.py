"""Polyanya: exact any-angle shortest paths on a navigation mesh, online, without preprocessing.

Cui, Harabor and Grastien, "Compromise-free pathfinding on a navigation mesh", IJCAI 2017.
The search is A* over *search nodes* ``(I, r)`` (sec. 3): a root ``r`` (the start or a mesh
vertex where the path last turned) and an interval ``I = [L, R]``, a contiguous part of one
polygon edge every point of which ``r`` sees. ``g`` is the length of the path to ``r``;
``f = g + h`` with ``h`` the length of the shortest path from ``r`` through ``I`` to the goal
(sec. 3.2: the goal is reflected across the line of ``I`` when it is on the root's side, then
``h = |r t'|`` when the segment ``r t'`` crosses ``I`` and ``|r p| + |p t'|`` through the
nearer endpoint ``p`` otherwise). ``h`` never overestimates and ``f`` never decreases along a
search path, so the first goal node popped is optimal (Theorem 1).

Successors (sec. 3.1, Figs. 2-3): the rays from ``r`` through ``L`` and ``R`` are projected
through the polygon ``P`` beyond ``I``. The part of ``P``'s far boundary between the rays gives
*observable* successors (same root, split at ``P``'s vertices so each interval lies on one
edge). When ``R`` (or ``L``) is the end of the edge and a *corner* (a vertex beside an
obstacle), the far boundary beyond the ray gives *non-observable* successors rooted at that
vertex, with ``g' = g + |r R|``. A successor whose root lies on the line of its interval (a
root at one of the edge's ends: the path turned at that vertex and enters the next polygon
directly) sees the whole next polygon; its expansion makes every far edge observable.

Pruning (sec. 4), each exact and each switchable (``prune=False`` gives the same lengths; tests
check it):

* dead ends: a successor whose polygon has no exit but the edge it enters by, and holds no
  goal, is dropped;
* intermediate polygons: a node with exactly one successor has it expanded at once instead of
  going through the open list;
* root-level pruning (the paper's closed list): the best ``g`` seen for each root vertex is
  kept; a node whose root was reached more cheaply is dropped at generation and when popped.

The goal (sec. 3.3): when the polygon beyond an interval holds the goal, the only successor is
the final node, ``f = g + h`` (``P`` is convex, so the goal is seen from the interval's optimal
point). Start and goal in one polygon: the straight segment. Points on an edge or a vertex
belong to every polygon around them; the start is expanded in each (its edges through the start
skipped). A point outside every polygon has no path.

Deviations from the paper, named: ``h`` through an interval whose root lies on its line is the
nearer endpoint's detour (exact there, the paper does not spell it out); turning is allowed at
every vertex with an obstacle beside it (the paper's corner rule), not only at reflex ones, which
adds successors but no wrong answers; tolerances are relative to the mesh size
(:data:`weldplan.planar.navmesh.REL_EPS`) where the authors' code uses an absolute ``1e-8``.
"""

from __future__ import annotations

import heapq
import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

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


def _h(
    rx: float, ry: float, lx: float, ly: float, qx: float, qy: float, tx: float, ty: float
) -> tuple[float, int]:
    """Paper sec. 3.2: shortest ``|r x| + |x t|`` over ``x`` in the interval ``[L, R]`` (here
    ``L = (lx, ly)``, ``R = (qx, qy)``), the goal reflected across the interval's line when on
    the root's side. Returns ``(h, via)``: ``via`` 0 when the straight segment crosses the
    interval, -1 through ``L``, 1 through ``R``."""
    dx, dy = qx - lx, qy - ly
    sr = dx * (ry - ly) - dy * (rx - lx)
    st = dx * (ty - ly) - dy * (tx - lx)
    if sr * st > 0.0:  # same side: reflect t across the line L R
        d2 = dx * dx + dy * dy
        k = 2.0 * st / d2
        tx, ty = tx + k * dy, ty - k * dx
    # t' in the wedge: left of (or on) the ray r->R and right of (or on) the ray r->L
    if sr != 0.0:
        cr = (qx - rx) * (ty - ry) - (qy - ry) * (tx - rx)
        cl = (lx - rx) * (ty - ry) - (ly - ry) * (tx - rx)
        if cr >= 0.0 and cl <= 0.0:
            return math.hypot(tx - rx, ty - ry), 0
    hl = math.hypot(lx - rx, ly - ry) + math.hypot(tx - lx, ty - ly)
    hr = math.hypot(qx - rx, qy - ry) + math.hypot(tx - qx, ty - qy)
    return (hl, -1) if hl <= hr else (hr, 1)


class Polyanya:
    """Polyanya queries on one :class:`NavMesh` (nothing is precomputed beyond the mesh).

    Parameters
    ----------
    mesh
        The navigation mesh.
    prune
        The paper's pruning (sec. 4; see the module docstring). ``False`` is the starved
        variant used by the tests: slower, same lengths.
    """

    def __init__(self, mesh: NavMesh, *, prune: bool = True) -> None:
        self.mesh = mesh
        self.prune = prune

    def distance(self, start: ArrayLike, goal: ArrayLike) -> float:
        """Shortest path length, ``inf`` when none exists (or a point is off the mesh)."""
        return self.query(start, goal).length

    def query(self, start: ArrayLike, goal: ArrayLike) -> PolyanyaResult:
        """Shortest any-angle path from ``start (2,)`` to ``goal (2,)``."""
        m = self.mesh
        s = np.asarray(start, dtype=np.float64).reshape(2)
        t = np.asarray(goal, dtype=np.float64).reshape(2)
        sx, sy, tx, ty = float(s[0]), float(s[1]), float(t[0]), float(t[1])
        none = PolyanyaResult(math.inf, np.zeros((0, 2)))
        spolys = m.locate(s)
        tpolys = m.locate(t)
        if not spolys or not tpolys:
            return none
        goal_polys = set(tpolys)
        if goal_polys.intersection(spolys):
            return PolyanyaResult(math.hypot(tx - sx, ty - sy), np.array([s, t]), 0, 0)
        return _Search(self, sx, sy, tx, ty, goal_polys).run(spolys) or none


class _Search:
    """The state of one query: open list, root records, best ``g`` per root vertex."""

    def __init__(
        self, owner: Polyanya, sx: float, sy: float, tx: float, ty: float, goal_polys: set[int]
    ) -> None:
        m = owner.mesh
        self.m = m
        self.prune = owner.prune
        self.tx, self.ty = tx, ty
        self.goal_polys = goal_polys
        self.eps = m.eps
        self.heap: list[tuple[Any, ...]] = []
        self.tick = 0
        # roots: (x, y, parent record) so the path can be read back
        self.roots: list[tuple[float, float, int]] = [(sx, sy, -1)]
        self.best_g: dict[int, float] = {}
        self.expanded = 0

    # a node is the tuple (f, tick, g, rx, ry, root_rec, root_vertex, lx, ly, qx, qy, poly, j):
    # interval L = (lx, ly), R = (qx, qy) on the entry edge j of polygon ``poly`` (L is its vertex
    # j, R its vertex j + 1 in poly's counter-clockwise order, up to the cuts of the projection)

    def run(self, spolys: list[int]) -> PolyanyaResult | None:
        m = self.m
        sx, sy, _ = self.roots[0]
        eps = self.eps
        vx, vy = m.vx, m.vy
        succ: list[tuple[Any, ...]] = []
        for p in spolys:
            vs, nb, op = m.polygons[p], m.neighbours[p], m.opposite[p]
            n = len(vs)
            for k in range(n):
                a, b = vs[k], vs[(k + 1) % n]
                ex, ey = vx[b] - vx[a], vy[b] - vy[a]
                if ex * (sy - vy[a]) - ey * (sx - vx[a]) <= eps * math.hypot(ex, ey):
                    continue  # the start lies on this edge's line: seen from the next polygon
                # seen from inside p, edge k's right end is a and its left end b
                self._push(succ, 0.0, sx, sy, 0, -1, vx[b], vy[b], vx[a], vy[a], nb[k], op[k])
        for node in succ:
            heapq.heappush(self.heap, node)
        heap = self.heap
        while heap:
            node = heapq.heappop(heap)
            if node[11] == -2:  # the final node
                return self._result(node)
            rv = node[6]
            if rv >= 0 and self.prune and node[2] > self.best_g.get(rv, math.inf) + eps:
                continue
            while node is not None:
                succ = []
                self._expand(node, succ)
                self.expanded += 1
                node = None
                if self.prune and len(succ) == 1 and succ[0][11] != -2:
                    node = succ[0]  # intermediate pruning: expand the lone successor now
                else:
                    for s in succ:
                        heapq.heappush(heap, s)
        return None

    def _push(
        self,
        out: list[tuple[Any, ...]],
        g: float,
        rx: float,
        ry: float,
        rec: int,
        rv: int,
        lx: float,
        ly: float,
        qx: float,
        qy: float,
        poly: int,
        j: int,
    ) -> None:
        """Append the successor with interval ``[L, R]`` entering ``poly`` by its edge ``j``,
        unless it is empty, leads into an obstacle or a dead end."""
        if poly < 0:
            return
        if abs(lx - qx) + abs(ly - qy) <= self.eps:
            return
        if self.prune and self.m.n_exits[poly] <= 1 and poly not in self.goal_polys:
            return  # dead end
        h, _ = _h(rx, ry, lx, ly, qx, qy, self.tx, self.ty)
        self.tick += 1
        out.append((g + h, self.tick, g, rx, ry, rec, rv, lx, ly, qx, qy, poly, j))

    def _new_root(self, g: float, v: int, rec: int) -> int:
        """Record root vertex ``v`` reached with ``g``; ``-1`` when root-level pruning drops it."""
        if self.prune:
            best = self.best_g.get(v, math.inf)
            if g > best + self.eps:
                return -1
            if g < best:
                self.best_g[v] = g
        m = self.m
        self.roots.append((m.vx[v], m.vy[v], rec))
        return len(self.roots) - 1

    def _expand(self, node: tuple[Any, ...], out: list[tuple[Any, ...]]) -> None:
        _, _, g, rx, ry, rec, rv, lx, ly, qx, qy, poly, j = node
        m = self.m
        eps = self.eps
        vs, nb, op = m.polygons[poly], m.neighbours[poly], m.opposite[poly]
        n = len(vs)
        vx, vy = m.vx, m.vy
        if poly in self.goal_polys:
            h, via = _h(rx, ry, lx, ly, qx, qy, self.tx, self.ty)
            turn = (lx, ly) if via == -1 else (qx, qy) if via == 1 else None
            self.tick += 1
            out.append((g + h, self.tick, g, rx, ry, rec, rv, turn, None, None, None, -2, -1))
            return
        # far boundary: ks[0] = R's vertex (j + 1) ... ks[n - 1] = L's vertex (j)
        ks = [vs[(j + 1 + i) % n] for i in range(n)]
        ei = [(j + 1 + i) % n for i in range(n - 1)]  # edge index of far edge i in poly
        px = [vx[k] for k in ks]
        py = [vy[k] for k in ks]
        dRx, dRy = qx - rx, qy - ry
        dLx, dLy = lx - rx, ly - ry
        wedge = dRx * dLy - dRy * dLx  # > 0: L left of the ray r->R
        nR = math.hypot(dRx, dRy)
        nL = math.hypot(dLx, dLy)
        if wedge <= eps * max(nR, nL):
            # the root is on the interval's line, at one of the edge's ends: it sees all of poly
            for i in range(n - 1):
                e = ei[i]
                self._push(
                    out, g, rx, ry, rec, rv, px[i + 1], py[i + 1], px[i], py[i], nb[e], op[e]
                )
            return
        cr = [dRx * (py[i] - ry) - dRy * (px[i] - rx) for i in range(n)]
        cl = [dLx * (py[i] - ry) - dLy * (px[i] - rx) for i in range(n)]
        tR = eps * nR
        tL = eps * nL
        # the right ray leaves poly on far edge ir, the left ray on far edge il
        i = 1
        while i < n - 1 and cr[i] <= tR:
            i += 1
        ir = i - 1
        i = n - 2
        while i > 0 and cl[i] >= -tL:
            i -= 1
        il = i
        if il < ir:  # rounding in a needle-thin wedge
            il = ir
        if cr[ir] <= tR and cr[ir] >= -tR:
            xrx, xry = px[ir], py[ir]
        else:
            s = cr[ir] / (cr[ir] - cr[ir + 1])
            xrx, xry = px[ir] + s * (px[ir + 1] - px[ir]), py[ir] + s * (py[ir + 1] - py[ir])
        if cl[il + 1] <= tL and cl[il + 1] >= -tL:
            xlx, xly = px[il + 1], py[il + 1]
        else:
            s = cl[il] / (cl[il] - cl[il + 1])
            xlx, xly = px[il] + s * (px[il + 1] - px[il]), py[il] + s * (py[il + 1] - py[il])
        # observable successors: same root
        for i in range(ir, il + 1):
            ax, ay = (xrx, xry) if i == ir else (px[i], py[i])
            bx, by = (xlx, xly) if i == il else (px[i + 1], py[i + 1])
            e = ei[i]
            self._push(out, g, rx, ry, rec, rv, bx, by, ax, ay, nb[e], op[e])
        # non-observable successors: the path turns at R's (or L's) vertex when it is a corner
        v = ks[0]
        if m.corner[v] and abs(qx - px[0]) + abs(qy - py[0]) <= eps:
            g2 = g + nR
            rec2 = self._new_root(g2, v, rec)
            if rec2 >= 0:
                for i in range(ir + 1):
                    bx, by = (xrx, xry) if i == ir else (px[i + 1], py[i + 1])
                    e = ei[i]
                    self._push(out, g2, px[0], py[0], rec2, v, bx, by, px[i], py[i], nb[e], op[e])
        v = ks[n - 1]
        if m.corner[v] and abs(lx - px[n - 1]) + abs(ly - py[n - 1]) <= eps:
            g2 = g + nL
            rec2 = self._new_root(g2, v, rec)
            if rec2 >= 0:
                for i in range(il, n - 1):
                    ax, ay = (xlx, xly) if i == il else (px[i], py[i])
                    e = ei[i]
                    self._push(
                        out,
                        g2,
                        px[n - 1],
                        py[n - 1],
                        rec2,
                        v,
                        px[i + 1],
                        py[i + 1],
                        ax,
                        ay,
                        nb[e],
                        op[e],
                    )

    def _result(self, node: tuple[Any, ...]) -> PolyanyaResult:
        f, _, _, rx, ry, rec, _, turn = node[:8]
        pts = [(self.tx, self.ty)]
        if turn is not None:
            pts.append(turn)
        while rec >= 0:
            x, y, rec = self.roots[rec]
            pts.append((x, y))
        P = np.array(pts[::-1], dtype=np.float64)
        return PolyanyaResult(float(f), P, self.expanded, self.tick)


def polyanya_path(mesh: NavMesh, start: ArrayLike, goal: ArrayLike) -> PolyanyaResult:
    """One query on ``mesh`` (see :class:`Polyanya`)."""
    return Polyanya(mesh).query(start, goal)
