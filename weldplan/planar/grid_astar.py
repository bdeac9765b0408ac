"""Exact shortest paths on occupancy grids: 8-connected A* and scipy Dijkstra, the rules of the
Moving AI benchmarks (octile costs 1 and sqrt 2, no corner cutting: a diagonal move needs both
orthogonal neighbours free).
"""

from __future__ import annotations

import heapq
import logging
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from weldplan.errors import PlanningError
from weldplan.planar.exact_path import ExactPath

log = logging.getLogger(__name__)

SQRT2 = math.sqrt(2.0)


def astar_grid(free: ArrayLike, start: tuple[int, int], goal: tuple[int, int]) -> ExactPath:
    """Shortest 8-connected path on a grid without corner cutting (octile costs).

    Parameters
    ----------
    free
        ``(nx, ny) bool``: traversable cells, indexed ``[i, j]``.
    start, goal
        Cell indices ``(i, j)``.

    Returns
    -------
    :class:`ExactPath` whose points are the cells ``(i, j)`` of the path (as floats) and whose
    length is in cells. A heap-based A* with the octile heuristic (consistent, so the first
    time the goal is popped its cost is optimal).

    Raises
    ------
    PlanningError
        When start or goal is blocked or the goal is unreachable.
    """
    F = np.asarray(free, dtype=bool)
    nx, ny = F.shape
    (si, sj), (gi, gj) = _free_cell(F, start, "start"), _free_cell(F, goal, "goal")
    # flat indices over a padded grid so that neighbours never wrap
    W = ny + 2
    pad = np.zeros((nx + 2, ny + 2), dtype=bool)
    pad[1:-1, 1:-1] = F
    ok = pad.ravel().tolist()
    s = (si + 1) * W + sj + 1
    t = (gi + 1) * W + gj + 1
    n_all = len(ok)
    g_cost = [math.inf] * n_all
    parent = [-1] * n_all
    closed = bytearray(n_all)
    g_cost[s] = 0.0
    gx, gy = gi + 1, gj + 1
    sq2 = SQRT2
    k2 = SQRT2 - 2.0
    # (offset, cost, orthogonal neighbours a diagonal move needs free)
    moves = (
        (W, 1.0, 0, 0),
        (-W, 1.0, 0, 0),
        (1, 1.0, 0, 0),
        (-1, 1.0, 0, 0),
        (W + 1, sq2, W, 1),
        (W - 1, sq2, W, -1),
        (-W + 1, sq2, -W, 1),
        (-W - 1, sq2, -W, -1),
    )

    def h(v: int) -> float:
        dx = abs(v // W - gx)
        dy = abs(v % W - gy)
        return dx + dy + k2 * (dx if dx < dy else dy)

    heap = [(h(s), 0.0, s)]
    push, pop = heapq.heappush, heapq.heappop
    expanded = 0
    while heap:
        _, gc, v = pop(heap)
        if closed[v]:
            continue
        if v == t:
            break
        closed[v] = 1
        expanded += 1
        for d, c, a, b in moves:
            u = v + d
            if not ok[u] or closed[u] or (a and not (ok[v + a] and ok[v + b])):
                continue
            nc = gc + c
            if nc < g_cost[u]:
                g_cost[u] = nc
                parent[u] = v
                push(heap, (nc + h(u), nc, u))
    else:
        raise PlanningError(f"goal cell {(gi, gj)} cannot be reached from {(si, sj)}")
    return ExactPath(
        points=_cells_back(parent, t, W), length=float(g_cost[t]), method="astar-8",
        expanded=expanded,
    )  # fmt: skip


def _free_cell(F: NDArray[np.bool_], cell: tuple[int, int], name: str) -> tuple[int, int]:
    """``cell`` as ints, checked to be a free cell of ``F``.

    Raises
    ------
    PlanningError
        When the cell is blocked or outside the grid.
    """
    a, b = int(cell[0]), int(cell[1])
    if not (0 <= a < F.shape[0] and 0 <= b < F.shape[1]) or not F[a, b]:
        raise PlanningError(f"{name} cell {(a, b)} is blocked or outside the grid")
    return a, b


def _cells_back(parent: list[int], t: int, W: int) -> tuple[tuple[float, float], ...]:
    """The cells ``(i, j)`` from the start to flat node ``t`` of the padded grid (row width
    ``W``), traced back through ``parent`` (-1 at the start)."""
    cells = []
    v = t
    while v != -1:
        cells.append((float(v // W - 1), float(v % W - 1)))
        v = parent[v]
    cells.reverse()
    return tuple(cells)


#: the eight moves of the Moving AI grids: (di, dj)
_MOVES8 = ((1, 0), (0, 1), (1, 1), (1, -1))


def grid_graph(free: ArrayLike) -> Any:
    """The 8-connected grid of :func:`astar_grid` as a sparse graph (scipy CSR, undirected).

    Node ``i * ny + j`` is cell ``(i, j)``; straight moves cost 1, diagonal ones sqrt(2) and
    need both orthogonal neighbours free (no corner cutting), exactly the moves of
    :func:`astar_grid`. Built with numpy in one pass per direction (a 512 x 512 map: 0.2 s).
    """
    from scipy.sparse import csr_matrix

    F = np.asarray(free, dtype=bool)
    nx, ny = F.shape
    I, J = np.nonzero(F)
    rows, cols, cost = [], [], []
    for di, dj in _MOVES8:
        I2, J2 = I + di, J + dj
        ok = (I2 >= 0) & (I2 < nx) & (J2 >= 0) & (J2 < ny)
        a, b, a2, b2 = I[ok], J[ok], I2[ok], J2[ok]
        ok = F[a2, b2]
        if di and dj:
            ok &= F[a + di, b] & F[a, b + dj]
        rows.append(a[ok] * ny + b[ok])
        cols.append(a2[ok] * ny + b2[ok])
        cost.append(np.full(int(ok.sum()), SQRT2 if di and dj else 1.0))
    r, c, w = np.concatenate(rows), np.concatenate(cols), np.concatenate(cost)
    return csr_matrix((w, (r, c)), shape=(nx * ny, nx * ny))


def grid_lengths(
    free: ArrayLike,
    starts: ArrayLike,
    goals: ArrayLike,
    *,
    graph: Any = None,
    limits: ArrayLike | None = None,
) -> NDArray[np.float64]:
    """Shortest 8-connected lengths (cells) for many queries, by scipy's compiled Dijkstra.

    The same graph as :func:`astar_grid` (see :func:`grid_graph`), one single-source search
    per query in C: about 0.05 s a query on a 512 x 512 map where the Python A* takes up to
    0.8 s (it floods mazes whatever the heuristic). ``limits (n,)``, when given, stop each
    search beyond that length (``inf`` is returned past it): a bound on the work, never a
    change to a length found within it.

    Parameters
    ----------
    free
        ``(nx, ny) bool`` traversable cells.
    starts, goals
        ``(n, 2)`` cell indices.
    graph
        A prebuilt :func:`grid_graph` of ``free`` (built here when None).
    limits
        Optional ``(n,)`` search bounds.

    Returns
    -------
    ``(n,)`` lengths in cells; ``inf`` where the goal is unreachable (or beyond its limit).
    """
    from scipy.sparse.csgraph import dijkstra as sp_dijkstra

    F = np.asarray(free, dtype=bool)
    ny = F.shape[1]
    G = grid_graph(F) if graph is None else graph
    S = np.asarray(starts, dtype=np.int64).reshape(-1, 2)
    T = np.asarray(goals, dtype=np.int64).reshape(-1, 2)
    out = np.full(len(S), np.inf)
    for k in range(len(S)):
        s = int(S[k, 0] * ny + S[k, 1])
        t = int(T[k, 0] * ny + T[k, 1])
        lim = np.inf if limits is None else float(np.asarray(limits)[k])
        d = sp_dijkstra(G, directed=False, indices=s, limit=lim)
        out[k] = d[t]
    return out


def octile(di: ArrayLike, dj: ArrayLike) -> NDArray[np.float64]:
    """Octile distance for cell offsets (the A* heuristic, exact on an empty grid)."""
    a = np.abs(np.asarray(di, dtype=np.float64))
    b = np.abs(np.asarray(dj, dtype=np.float64))
    return a + b + (SQRT2 - 2.0) * np.minimum(a, b)
